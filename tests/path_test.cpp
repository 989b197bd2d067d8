// The reference path tracer against analytic answers: irradiance under a point light, a white
// furnace, energy through a glass slab, and bit-identical images whatever the thread count.
#include <gtest/gtest.h>

#include <cstring>

#include "scene/accel.h"
#include "scene/bsdf.h"
#include "scene/lights.h"
#include "path/path.h"
#include "render.h"
#include "core/sampling.h"
#include "test_scenes.h"

using namespace rs;
using namespace rs::test;

namespace {

Vec3 meanRadiance(const Scene& scene, Vec3 origin, Vec3 dir, int paths, uint64_t seed = 1, int maxDepth = 256) {
    RayAccel accel(scene, 1);
    LightSampler lights(scene);
    DVec3 sum(0.0);
    for (int i = 0; i < paths; ++i) {
        Sampler sampler(seed, Stage::Test, uint64_t(i));
        sum += DVec3(tracePath(scene, accel, lights, origin, dir, maxDepth, sampler).total());
    }
    return Vec3(sum / double(paths));
}

}  // namespace

// L = ρ/π · I·cosθ/r² on a diffuse plane lit by a point light and nothing else.
TEST(PathTracer, PointLightIrradianceOnDiffusePlane) {
    Scene s;
    const float rho = 0.5f;
    uint32_t m = addMaterial(s, MaterialKind::Lambert, Vec3(rho));
    addQuad(s, {-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}, m);
    PunctualLight l;
    l.type = LightType::Point;
    l.position = {0.3f, 2.f, -0.2f};
    l.intensity = Vec3(10.f, 20.f, 5.f);
    s.lights.push_back(l);
    s.computeBounds();
    RayAccel accel(s, 1);
    LightSampler lights(s);

    for (Vec3 target : {Vec3(0.3f, 0, -0.2f), Vec3(1.f, 0, 1.f), Vec3(-3.f, 0, 2.f), Vec3(6.f, 0, -4.f)}) {
        Vec3 eye = target + Vec3(0.4f, 1.f, 0.7f);
        Sampler sampler(7, Stage::Test, 0);
        // One path is exact: the light is a delta, the plane sees nothing else.
        Vec3 L = tracePath(s, accel, lights, eye, glm::normalize(target - eye), 8, sampler).total();
        Vec3 d = l.position - target;
        float r2 = glm::dot(d, d), cosTheta = d.y / std::sqrt(r2);
        Vec3 expected = rho / kPi * l.intensity * cosTheta / r2;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(L[c], expected[c], 1e-4f * expected[c]) << "target " << target.x << "," << target.z;
    }
}

// Spot light: full intensity inside the inner cone, nothing outside the outer cone.
TEST(PathTracer, SpotLightConeLimitsIrradiance) {
    Scene s;
    uint32_t m = addMaterial(s, MaterialKind::Lambert, Vec3(1.f));
    addQuad(s, {-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}, m);
    PunctualLight l;
    l.type = LightType::Spot;
    l.position = {0, 2, 0};
    l.direction = {0, -1, 0};
    l.intensity = Vec3(4.f);
    l.cosInner = std::cos(0.3f);
    l.cosOuter = std::cos(0.5f);
    s.lights.push_back(l);
    s.computeBounds();
    RayAccel accel(s, 1);
    LightSampler lights(s);
    auto radianceAt = [&](Vec3 target) {
        Sampler sampler(3, Stage::Test, 0);
        return tracePath(s, accel, lights, target + Vec3(0, 1, 0.1f), glm::normalize(Vec3(0, -1, -0.1f)), 8, sampler).total().x;
    };
    float inside = radianceAt({0.2f, 0, 0});  // 0.1 rad off axis
    float r2 = 4.f + 0.04f, cosT = 2.f / std::sqrt(r2);
    EXPECT_NEAR(inside, kInvPi * 4.f * cosT / r2, 1e-4f);
    EXPECT_EQ(radianceAt({2.f, 0, 0}), 0.f);  // 0.79 rad off axis: outside the outer cone
}

// A plate 0.78 m under a small ceiling light, like the top of the Cornell box's tall box:
// its radiance is ρ/π times the irradiance of Lambert's polygon formula. The light is seen at
// low elevation from the plate's far points, where shadow rays that overshoot the light by
// the origin offset used to hit the light itself (a 3× deficit that Mitsuba exposed).
TEST(PathTracer, AreaLightIrradianceNearTheLightMatchesLambertsFormula) {
    Scene s;
    const float rho = 0.75f, h = 1.98f;
    const Vec3 Le(20.f);
    uint32_t plate = addMaterial(s, MaterialKind::Lambert, Vec3(rho));
    uint32_t light = addMaterial(s, MaterialKind::Lambert, Vec3(0.f), Le);
    addQuad(s, {-1.5f, 1.2f, -1.5f}, {-1.5f, 1.2f, 1.5f}, {1.5f, 1.2f, 1.5f}, {1.5f, 1.2f, -1.5f}, plate);
    const Vec3 corners[4] = {{-0.25f, h, -0.2f}, {0.25f, h, -0.2f}, {0.25f, h, 0.2f}, {-0.25f, h, 0.2f}};
    addQuad(s, corners[0], corners[1], corners[2], corners[3], light);  // faces down
    s.computeBounds();

    for (Vec3 target : {Vec3(0.f, 1.2f, 0.f), Vec3(-0.585f, 1.2f, -0.335f), Vec3(1.1f, 1.2f, 0.4f)}) {
        // Lambert: E = Le/2 · Σ βᵢ (n · unit(vᵢ × vᵢ₊₁)) over the polygon's edges seen from target.
        double e = 0.0;
        for (int i = 0; i < 4; ++i) {
            DVec3 a = DVec3(corners[i] - target), b = DVec3(corners[(i + 1) % 4] - target);
            DVec3 c = glm::cross(a, b);
            e += std::acos(glm::dot(glm::normalize(a), glm::normalize(b))) * glm::normalize(c).y;
        }
        double expected = rho / kPi * 0.5 * Le.x * std::abs(e);
        Vec3 eye = target + Vec3(0.05f, 0.3f, 0.1f);
        Vec3 L = meanRadiance(s, eye, glm::normalize(target - eye), 20000, 5, 2);
        EXPECT_NEAR(L.x, expected, 0.02 * expected) << "target " << target.x << "," << target.z;
    }
}

// A closed diffuse sphere emitting Le everywhere inside: L = Le / (1 − ρ) in every direction.
TEST(PathTracer, WhiteFurnaceClosedSphere) {
    Scene s;
    const float rho = 0.6f, Le = 1.f;
    uint32_t m = addMaterial(s, MaterialKind::Lambert, Vec3(rho), Vec3(Le));
    addSphere(s, Vec3(0.f), 1.f, 3, m, /*inward=*/true);
    s.computeBounds();
    const int paths = 20000;
    Vec3 L = meanRadiance(s, Vec3(0.1f, -0.2f, 0.05f), glm::normalize(Vec3(0.3f, 0.5f, -0.8f)), paths);
    float expected = Le / (1.f - rho);  // 2.5
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(L[c], expected, 0.02f * expected);
}

// Glass slab, emitter of radiance Le behind it, nothing else: a ray through the slab sees
// Le · (1 − R)/(1 + R) (all internal reflections summed); with a second emitter on the camera
// side, reflected and transmitted light add up to Le — no energy made or lost (every path
// carries weight 1 whichever branch Fresnel picks; only Russian roulette adds noise).
TEST(PathTracer, GlassSlabTransmitsWhatFresnelAllows) {
    for (float angle : {0.f, 0.6f}) {
        for (bool lightBothSides : {false, true}) {
            Scene s;
            uint32_t glass = addMaterial(s, MaterialKind::Glass, Vec3(1.f));
            uint32_t emit = addMaterial(s, MaterialKind::Lambert, Vec3(0.f), Vec3(1.f));
            addBox(s, {-20, -20, -0.1f}, {20, 20, 0.1f}, glass);  // slab: z in [-0.1, 0.1]
            addQuad(s, {-100, -100, -3}, {100, -100, -3}, {100, 100, -3}, {-100, 100, -3}, emit);  // behind, faces +z
            if (lightBothSides) addQuad(s, {-100, -100, 3}, {-100, 100, 3}, {100, 100, 3}, {100, -100, 3}, emit);  // faces −z
            s.computeBounds();
            Vec3 dir = glm::normalize(Vec3(std::sin(angle), 0.f, -std::cos(angle)));
            Vec3 L = meanRadiance(s, Vec3(0.f, 0.f, 2.f), dir, 4000, 5);
            float R = fresnelDielectric(std::cos(angle), 1.5f);
            float expected = lightBothSides ? 1.f : (1.f - R) / (1.f + R);
            // Russian roulette on the few internally reflected paths is the only noise: σ ≈ 7e-4.
            EXPECT_NEAR(L.x, expected, lightBothSides ? 3e-3f : 0.01f) << "angle " << angle << " both " << lightBothSides;
        }
    }
}

// The same render with 1 and with 2 threads: identical pixels, bit for bit.
TEST(PathTracer, ThreadCountDoesNotChangePixels) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    Scene scene = loadScene(std::string(data) + "/glossy_box.glb", silentReporter());
    RenderConfig cfg;
    cfg.output = "unused.exr";
    cfg.method = Method::Path;
    cfg.width = 40;
    cfg.spp = 4;
    RenderResult a = expectSamePixelsWhateverTheThreadCount(scene, cfg);
    float sum = 0.f;
    for (size_t i = 0; i < a.film.pixelCount(); ++i) sum += luminance(a.film.beauty(i));
    EXPECT_GT(sum, 0.f);
}
