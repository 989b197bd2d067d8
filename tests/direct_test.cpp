// Direct light by sampling (--direct sample), in the direct film or at the eye samples, and progressive passes,
// against independent answers: Lambert's law for a point light, the path tracer, Fresnel
// through glass. Every light path must be counted once: what the shadow ray cannot reach
// through glass comes from caustic photons, neither lost nor doubled.
#include <gtest/gtest.h>

#include <cstring>

#include "scene/bsdf.h"
#include "core/log.h"
#include "render.h"
#include "test_scenes.h"

using namespace rs;
using namespace rs::test;

namespace {

RenderConfig sampledConfig(int width) {
    RenderConfig cfg;
    cfg.output = "unused.exr";
    cfg.width = width;
    cfg.height = width;
    cfg.grid = 96;
    cfg.voxelizer = "cpu";
    cfg.photons = 40000;
    cfg.passes = 1;
    return cfg;
}

double mean(const std::vector<Vec3>& px) {
    double s = 0.0;
    for (const Vec3& v : px) s += double(v.x) + v.y + v.z;
    return s / (3.0 * double(px.size()));
}

// A 4 m floor (ρ = 0.5) under a light 1.5 m up, seen from above.
Scene floorUnder(bool pointLight) {
    Scene s;
    uint32_t floor = addMaterial(s, MaterialKind::Lambert, Vec3(0.5f));
    addQuad(s, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, floor);
    if (pointLight) {
        PunctualLight l;
        l.position = {0.3f, 1.5f, 0.f};
        l.intensity = Vec3(4.f);
        s.lights.push_back(l);
    } else {
        uint32_t light = addMaterial(s, MaterialKind::Lambert, Vec3(0.f), Vec3(20.f));
        addQuad(s, {-0.1f, 1.5f, -0.1f}, {0.1f, 1.5f, -0.1f}, {0.1f, 1.5f, 0.1f}, {-0.1f, 1.5f, 0.1f}, light);
    }
    s.cameras.push_back(lookAt({0.f, 3.f, 0.01f}, {0.f, 0.f, 0.f}, {0.f, 0.f, -1.f}, 1.2f));
    s.computeBounds();
    return s;
}

}  // namespace

// A point light needs one shadow ray: every pixel's direct light is Lambert's ρ/π·I·cos/r²
// at its eye samples — no kernel, no noise. The path tracer's next-event estimate is the same
// law, so the two agree up to where in the pixel they sampled.
TEST(DirectBySampling, PointLightIsExactPerPixel) {
    Scene s = floorUnder(true);
    RenderConfig cfg = sampledConfig(32);
    cfg.photons = 1000;  // the floor alone has no indirect light worth tracing
    RenderResult r = render(s, cfg, silentReporter());
    RenderConfig path = cfg;
    path.method = Method::Path;
    path.spp = 64;
    RenderResult ref = render(s, path, silentReporter());
    double worst = 0.0;
    for (int y = 4; y < 28; ++y) {  // inside the floor's edges, which cut through border pixels
        for (int x = 4; x < 28; ++x) {
            float a = r.film.layers[kDirect][size_t(y) * 32 + x].x, b = ref.film.layers[kDirect][size_t(y) * 32 + x].x;
            worst = std::max(worst, double(std::abs(a / b - 1.f)));
        }
    }
    EXPECT_LT(worst, 0.02);
    EXPECT_NEAR(mean(r.film.layers[kDirect]) / mean(ref.film.layers[kDirect]), 1.0, 2e-3);
}

// A small area light: the mean direct light over the floor matches the path tracer's, and
// more light samples only lower the noise.
TEST(DirectBySampling, AreaLightMatchesThePathTracer) {
    Scene s = floorUnder(false);
    RenderConfig cfg = sampledConfig(32);
    cfg.photons = 1000;
    RenderConfig path = cfg;
    path.method = Method::Path;
    path.spp = 1024;
    RenderResult ref = render(s, path, silentReporter());
    double want = mean(ref.film.layers[kDirect]);
    for (int n : {1, 8}) {
        cfg.lightSamples = n;
        RenderResult r = render(s, cfg, silentReporter());
        EXPECT_NEAR(mean(r.film.layers[kDirect]) / want, 1.0, 0.02) << n << " light samples";
    }
}

namespace {

double relativeMseOf(const std::vector<Vec3>& a, const std::vector<Vec3>& ref) {
    double sum = 0.0;
    for (size_t i = 0; i < a.size(); ++i)
        for (int c = 0; c < 3; ++c) sum += sqr(double(a[i][c]) - ref[i][c]) / (sqr(double(ref[i][c])) + 0.01);
    return sum / (3.0 * double(a.size()));
}

// The floor under a point light, with a box on it casting a hard shadow across the view.
Scene boxShadowUnderPointLight() {
    Scene s = floorUnder(true);
    uint32_t white = addMaterial(s, MaterialKind::Lambert, Vec3(0.7f));
    addBox(s, {-0.35f, 0.f, -0.3f}, {0.05f, 0.6f, 0.25f}, white);
    s.computeBounds();
    return s;
}

}  // namespace

// The direct film (its own camera samples, apart from the receivers) is the path tracer's
// direct light: over the floor and the box, and across the box's hard shadow, every 4 × 4
// block's mean agrees within 3 %, with either light.
TEST(DirectFilm, MatchesThePathTracersDirectLightBlockByBlock) {
    for (bool point : {true, false}) {
        Scene s = point ? boxShadowUnderPointLight() : floorUnder(false);
        if (!point) addBox(s, {-0.35f, 0.f, -0.3f}, {0.05f, 0.6f, 0.25f}, addMaterial(s, MaterialKind::Lambert, Vec3(0.7f)));
        s.computeBounds();
        RenderConfig cfg = sampledConfig(32);
        cfg.photons = 1000;
        cfg.passes = 4;
        RenderResult r = render(s, cfg, silentReporter());
        RenderConfig path = cfg;
        path.method = Method::Path;
        path.passes = 1;
        path.spp = 4096;
        RenderResult ref = render(s, path, silentReporter());
        double worst = 0.0;
        for (int by = 1; by < 7; ++by)  // inside the floor's edges
            for (int bx = 1; bx < 7; ++bx) {
                double a = 0.0, b = 0.0;
                for (int y = 4 * by; y < 4 * by + 4; ++y)
                    for (int x = 4 * bx; x < 4 * bx + 4; ++x) {
                        a += r.film.layers[kDirect][size_t(y) * 32 + x].x;
                        b += ref.film.layers[kDirect][size_t(y) * 32 + x].x;
                    }
                if (b > 1e-3) worst = std::max(worst, std::abs(a / b - 1.0));
            }
        RecordProperty(std::string("worst_block_") + (point ? "point" : "area"), std::to_string(worst));
        EXPECT_LT(worst, 0.03) << (point ? "point light" : "area light");
    }
}

// A hard shadow edge wants camera samples, not light samples: at the same passes the direct
// film (16 camera samples a pixel, one light sample each) puts the point light's shadow edge
// with less than half the error of the receivers' own samples (4 a pixel, 8 light samples each).
TEST(DirectFilm, SharpensHardShadowEdgesOverTheReceiversSamples) {
    Scene s = boxShadowUnderPointLight();
    RenderConfig cfg = sampledConfig(48);
    cfg.photons = 1000;
    cfg.passes = 2;
    RenderConfig path = cfg;
    path.method = Method::Path;
    path.passes = 1;
    path.spp = 4096;
    const std::vector<Vec3> ref = render(s, path, silentReporter()).film.layers[kDirect];
    const double film = relativeMseOf(render(s, cfg, silentReporter()).film.layers[kDirect], ref);
    cfg.directSpp = 0;
    cfg.lightSamples = 8;
    const double receivers = relativeMseOf(render(s, cfg, silentReporter()).film.layers[kDirect], ref);
    RecordProperty("rel_mse_film", std::to_string(film));
    RecordProperty("rel_mse_receivers", std::to_string(receivers));
    EXPECT_LT(film, 0.5 * receivers);
}

namespace {

// The floor lit by a light only through a glass sheet 2 cm thick that covers it: the camera
// sits under the sheet. Shadow rays meet the glass, so direct light by sampling finds
// nothing and the light must come from caustic photons.
Scene floorUnderGlass(bool pointLight) {
    Scene s;
    uint32_t floor = addMaterial(s, MaterialKind::Lambert, Vec3(0.5f));
    uint32_t glass = addMaterial(s, MaterialKind::Glass, Vec3(1.f));
    addQuad(s, {-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}, floor);
    addBox(s, {-3.f, 0.5f, -3.f}, {3.f, 0.52f, 3.f}, glass);
    if (pointLight) {
        PunctualLight l;
        l.position = {0.f, 1.2f, 0.f};
        l.intensity = Vec3(2.f);
        s.lights.push_back(l);
    } else {
        uint32_t light = addMaterial(s, MaterialKind::Lambert, Vec3(0.f), Vec3(40.f));
        addQuad(s, {-0.1f, 1.2f, -0.1f}, {0.1f, 1.2f, -0.1f}, {0.1f, 1.2f, 0.1f}, {-0.1f, 1.2f, 0.1f}, light);
    }
    s.cameras.push_back(lookAt({0.f, 0.4f, 1.6f}, {0.f, 0.f, 0.f}, {0.f, 1.f, 0.f}, 1.0f));
    s.computeBounds();
    return s;
}

}  // namespace

// Area light through glass: the floor's light is the path tracer's (all of it caustic), not
// black (lost) and not twice it (counted by both the shadow ray and the photons).
TEST(DirectBySampling, LightThroughGlassComesOnceFromCausticPhotons) {
    Scene s = floorUnderGlass(false);
    RenderConfig cfg = sampledConfig(32);
    cfg.photons = 200000;
    for (int c = 0; c < 3; ++c) cfg.minRadius[c] = 1.f, cfg.maxRadius[c] = 4.f;
    RenderResult r = render(s, cfg, silentReporter());
    RenderConfig path = cfg;
    path.method = Method::Path;
    path.spp = 4096;
    RenderResult ref = render(s, path, silentReporter());
    EXPECT_EQ(mean(r.film.layers[kDirect]), 0.0) << "the shadow rays meet the glass";
    double got = mean(r.film.beautyImage()), want = mean(ref.film.beautyImage());
    EXPECT_GT(want, 0.0);
    EXPECT_NEAR(got / want, 1.0, 0.03);
}

// A point light through glass: the path tracer cannot see it at all (no shadow ray passes
// glass, no BSDF sample finds a point), so the answer is analytic: Lambert's law times the
// two interfaces' Fresnel transmission, T = (1 − R)² for a flat sheet (the sideways shift of
// 4 mm is negligible at 1.2 m). Checked under the light, where incidence is near normal.
TEST(DirectBySampling, PointLightThroughGlassComesFromCausticPhotons) {
    Scene s = floorUnderGlass(true);
    s.cameras[0] = lookAt({0.f, 0.45f, 0.01f}, {0.f, 0.f, 0.f}, {0.f, 0.f, -1.f}, 0.5f);  // a 0.23 m patch
    RenderConfig cfg = sampledConfig(16);
    cfg.photons = 400000;
    for (int c = 0; c < 3; ++c) cfg.minRadius[c] = 1.f, cfg.maxRadius[c] = 4.f;
    RenderResult r = render(s, cfg, silentReporter());
    EXPECT_EQ(mean(r.film.layers[kDirect]), 0.0);
    const float R = fresnelDielectric(1.f, 1.5f);
    double lambert = 0.5 / kPi * 2.0 / sqr(1.2);  // ρ/π · I / r² at the centre
    double want = lambert * sqr(1.0 - R);
    // The patch's falloff (cos³ over ±0.115 m) lowers the mean by under 1.5 %.
    EXPECT_NEAR(mean(r.film.layers[kCaustic]) / want, 0.99, 0.04);
}

// Energy balance in a closed room whose walls all emit Le and reflect ρ (a white furnace):
// radiance is Le/(1 − ρ) everywhere — Le seen directly, Le·ρ of sampled direct light, the
// rest from indirect photons. Nothing is lost between the two estimators or counted twice.
TEST(DirectBySampling, WhiteFurnaceRoomBalancesEnergy) {
    Scene s;
    const float rho = 0.5f, le = 1.f;
    uint32_t wall = addMaterial(s, MaterialKind::Lambert, Vec3(rho), Vec3(le));
    addBox(s, {-1, 0, -1}, {1, 2, 1}, wall, /*inward=*/true);
    s.cameras.push_back(lookAt({0.f, 1.f, 0.8f}, {0.f, 1.f, -1.f}, {0.f, 1.f, 0.f}, 1.4f));
    s.computeBounds();
    RenderConfig cfg = sampledConfig(24);
    cfg.photons = 100000;
    RenderResult r = render(s, cfg, silentReporter());
    const double want = le / (1.0 - rho);
    EXPECT_NEAR(mean(r.film.layers[kEmission]), le, 1e-4);
    EXPECT_NEAR(mean(r.film.layers[kDirect]) / (le * rho), 1.0, 0.02);
    EXPECT_NEAR(mean(r.film.beautyImage()) / want, 1.0, 0.03);
}

// Progressive passes converge: relative MSE against a 4096-spp path render falls from 1 to
// 4 to 16 passes (each pass's own noise is far above the reference's).
TEST(Passes, ErrorFallsWithEveryQuadrupling) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    Scene scene = loadScene(std::string(data) + "/cornell_box.gltf", silentReporter());
    RenderConfig cfg = sampledConfig(32);
    cfg.photons = 20000;
    RenderConfig path = cfg;
    path.method = Method::Path;
    path.spp = 4096;
    std::vector<Vec3> ref = render(scene, path, silentReporter()).film.beautyImage();
    double last = 1e30;
    for (int passes : {1, 4, 16}) {
        cfg.passes = passes;
        double e = relativeMse(render(scene, cfg, silentReporter()).film.beautyImage(), ref);
        RecordProperty("rel_mse_" + std::to_string(passes), std::to_string(e));
        EXPECT_LT(e, 0.7 * last) << passes << " passes";
        last = e;
    }
}

// Passes, sampled direct light and photons give the same pixels with 1 and 2 threads.
TEST(Passes, ThreadCountDoesNotChangePixels) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    Scene scene = loadScene(std::string(data) + "/glossy_box.glb", silentReporter());
    RenderConfig cfg = sampledConfig(24);
    cfg.photons = 5000;
    cfg.passes = 3;
    cfg.lightSamples = 2;
    expectSamePixelsWhateverTheThreadCount(scene, cfg);
}
