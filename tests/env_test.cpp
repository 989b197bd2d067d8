// The environment light (--env, --sky) against independent answers: its sampling density
// against its own radiance, Blender's orientation pixel by pixel, a floor under a uniform sky
// (L·ρ exactly), a floor under a sky with a bright patch (a brute-force sum over the image's
// pixels), and photons from the sky against the path tracer.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>

#include "core/error.h"
#include "core/log.h"
#include "core/sampling.h"
#include "output/image_io.h"
#include "render.h"
#include "core/parallel.h"
#include "scene/accel.h"
#include "scene/environment.h"
#include "scene/lights.h"
#include "splat/photons.h"
#include "test_scenes.h"

using namespace rs;
using namespace rs::test;

namespace {

// A 2:1 image: a dim blue-grey sky, a warm patch ("sun") 30° above the horizon towards
// u = 0.625, and a dark lower half.
Environment patchedSky(std::vector<Vec3>* pixelsOut = nullptr, float rotation = 0.f, int w = 64, int h = 32) {
    std::vector<Vec3> px(size_t(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            Vec3 L = y < h / 2 ? Vec3(0.4f, 0.5f, 0.7f) : Vec3(0.05f);
            if (y == h / 3 - 1 && (x == 5 * w / 8 || x == 5 * w / 8 + 1)) L = Vec3(400.f, 360.f, 300.f);
            px[size_t(y) * w + x] = L;
        }
    if (pixelsOut) *pixelsOut = px;
    return Environment::image(w, h, px, 1.f, rotation);
}

// The direction at image point (u, v) of Blender's equirectangular mapping, in glTF's frame:
// Blender (x, y, z) is glTF (x, z, −y); Blender's u = ½ − atan2(y, x)/2π, v from the top
// = acos(z)/π.
Vec3 blenderDirection(float u, float v) {
    const float phi = 2.f * kPi * (0.5f - u), theta = kPi * v;
    const Vec3 b(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    return {b.x, b.z, -b.y};
}

// A 40 m floor (ρ = 0.5) seen from 1 m above, looking down: no pixel sees past it.
Scene openFloor() {
    Scene s;
    s.path = "open floor";
    uint32_t floor = addMaterial(s, MaterialKind::Lambert, Vec3(0.5f));
    addQuad(s, {-20, 0, -20}, {-20, 0, 20}, {20, 0, 20}, {20, 0, -20}, floor);
    s.cameras.push_back(lookAt({0, 1, 0}, {0, 0, 0}, {0, 0, -1}, 0.6f));
    s.computeBounds();
    return s;
}

RenderConfig envConfig(int width) {
    RenderConfig cfg;
    cfg.output = "unused.exr";
    cfg.width = width;
    cfg.height = width;
    cfg.photons = 40000;
    cfg.passes = 2;
    return cfg;
}

// Writes `pixels` (w × h, top row first) as an EXR whose R, G, B are the image.
std::string writeEnvironment(const TempDir& dir, const std::vector<Vec3>& pixels, int w, int h) {
    Film film(w, h);
    film.layers[kEmission] = pixels;
    const std::string path = (dir.path() / "sky.exr").string();
    writeExrTo(path, path, film, {});
    return path;
}

}  // namespace

TEST(Environment, SamplingDensityMatchesItsOwnPdfAndIntegral) {
    const Environment env = patchedSky(nullptr, 0.7f);
    Sampler rng(1, Stage::Test, 0);
    DVec3 estimate(0.0);
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        float pdf;
        const Vec3 d = env.sample(rng.get2D(), pdf);
        ASSERT_GT(pdf, 0.f);
        ASSERT_NEAR(glm::length(d), 1.f, 1e-4f);
        EXPECT_NEAR(env.pdf(d), pdf, 2e-3f * pdf) << "direction " << d.x << "," << d.y << "," << d.z;
        estimate += DVec3(env.radiance(d)) / double(pdf);
    }
    estimate /= double(n);
    const Vec3 integral = env.integral();
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(estimate[c], integral[c], 0.01 * integral[c]);
    // The pdf integrates to one: a midpoint sum over 8 × 8 cells a pixel.
    double mass = 0.0;
    const int nu = 64 * 8, nv = 32 * 8;
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const double theta = kPi * (j + 0.5) / nv, phi = 2.0 * kPi * (i + 0.5) / nu;
            const Vec3 d(float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)), float(std::sin(theta) * std::sin(phi)));
            mass += env.pdf(d) * std::sin(theta) * (2.0 * kPi / nu) * (kPi / nv);
        }
    EXPECT_NEAR(mass, 1.0, 1e-3);
}

// Every pixel's centre, mapped as Blender maps it, reads that pixel back. Turned by 90° (a
// Mapping node's Z rotation turns the lookup direction +Z to +X), the image's centre column
// moves from +X to +Z: clockwise seen from above.
TEST(Environment, OrientedAsBlendersWorld) {
    const int w = 16, h = 8;
    std::vector<Vec3> px(size_t(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) px[size_t(y) * w + x] = Vec3(float(x), float(y), 1.f);
    const Environment env = Environment::image(w, h, px, 1.f, 0.f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Vec3 L = env.radiance(blenderDirection((x + 0.5f) / w, (y + 0.5f) / h));
            EXPECT_EQ(L.x, float(x)) << "pixel " << x << "," << y;
            EXPECT_EQ(L.y, float(y)) << "pixel " << x << "," << y;
        }
    EXPECT_EQ(env.radiance(Vec3(1, 0.01f, 0)).x, float(w / 2));
    EXPECT_EQ(env.radiance(Vec3(0, 1, 0)).y, 0.f);
    const Environment turned = Environment::image(w, h, px, 2.f, 0.5f * kPi);
    const Vec3 centre = turned.radiance(Vec3(-0.01f, 0.01f, 1));
    EXPECT_EQ(centre.x, float(2 * (w / 2)));
    EXPECT_EQ(centre.z, 2.f);
}

// Under a uniform sky of radiance L an unoccluded Lambert floor reflects exactly ρ·L, all of
// it direct; the camera sees only the floor. Path tracer and splat alike.
TEST(Environment, UniformSkyOnAnOpenFloorGivesAlbedoTimesRadiance) {
    const Scene scene = openFloor();
    RenderConfig cfg = envConfig(24);
    cfg.sky = Vec3(2.f, 1.f, 0.5f);
    const RenderResult splat = expectSamePixelsWhateverTheThreadCount(scene, cfg);
    cfg.method = Method::Path;
    cfg.spp = 256;
    const RenderResult path = render(scene, cfg, silentReporter());
    for (const RenderResult* r : {&splat, &path}) {
        DVec3 sum(0.0);
        for (const Vec3& v : r->film.layers[kDirect]) sum += DVec3(v);
        sum /= double(r->film.pixelCount());
        EXPECT_NEAR(sum.x, 1.0, 0.01);
        EXPECT_NEAR(sum.y, 0.5, 0.005);
        EXPECT_NEAR(sum.z, 0.25, 0.0025);
        EXPECT_LT(layerMean(r->film, kIndirect), 1e-3);
        EXPECT_EQ(layerMean(r->film, kEmission), 0.0);
    }
}

// A sky with a bright patch, read from an EXR: the floor's radiance is ρ/π · Σ L·cos θ·ΔΩ over
// the image's upper half, summed pixel by pixel (each pixel's solid angle exact, cos θ over it
// integrated in closed form). The patch holds most of the light: without importance sampling
// the estimate would be noise.
TEST(Environment, SkyWithABrightPatchMatchesTheBruteForceIrradiance) {
    TempDir dir;
    std::vector<Vec3> px;
    const int w = 64, h = 32;
    patchedSky(&px, 0.f, w, h);
    DVec3 irradiance(0.0);
    for (int y = 0; y < h / 2; ++y) {
        // ∫ cos θ sin θ dθ over the row, times 2π/w per pixel.
        const double t0 = kPi * y / h, t1 = kPi * (y + 1.0) / h;
        const double cosOmega = 2.0 * kPi / w * 0.5 * (std::sin(t1) * std::sin(t1) - std::sin(t0) * std::sin(t0));
        for (int x = 0; x < w; ++x) irradiance += DVec3(px[size_t(y) * w + x]) * cosOmega;
    }
    const DVec3 want = 0.5 / kPi * irradiance;

    const Scene scene = openFloor();
    RenderConfig cfg = envConfig(16);
    cfg.env = writeEnvironment(dir, px, w, h);
    const RenderResult splat = render(scene, cfg, silentReporter());
    cfg.method = Method::Path;
    cfg.spp = 64;
    const RenderResult path = render(scene, cfg, silentReporter());
    for (const RenderResult* r : {&splat, &path}) {
        DVec3 sum(0.0);
        for (const Vec3& v : r->film.layers[kDirect]) sum += DVec3(v);
        sum /= double(r->film.pixelCount());
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c], want[c], 0.02 * want[c]) << "channel " << c;
    }
}

// The camera sees the environment where nothing is in the way, in the emission layer.
TEST(Environment, CameraSeesTheSky) {
    Scene scene;
    scene.path = "empty";
    uint32_t m = addMaterial(scene, MaterialKind::Lambert, Vec3(0.5f));
    addQuad(scene, {-1, -5, -1}, {1, -5, -1}, {1, -5, 1}, {-1, -5, 1}, m);  // behind the camera
    scene.cameras.push_back(lookAt({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0.05f));
    scene.computeBounds();
    TempDir dir;
    const int w = 16, h = 8;
    std::vector<Vec3> px(size_t(w) * h, Vec3(0.1f));
    for (int y : {h / 2 - 1, h / 2})  // +X, about the horizon: the corners of four pixels
        for (int x : {w / 2 - 1, w / 2}) px[size_t(y) * w + x] = Vec3(3.f, 2.f, 1.f);
    RenderConfig cfg = envConfig(4);
    cfg.env = writeEnvironment(dir, px, w, h);
    cfg.envStrength = 0.5f;
    const RenderResult r = render(scene, cfg, silentReporter());
    for (const Vec3& v : r.film.layers[kEmission]) {
        EXPECT_FLOAT_EQ(v.x, 1.5f);
        EXPECT_FLOAT_EQ(v.z, 0.5f);
    }
}

// Photons from the sky: a floor and a wall meeting at a corner, open above. The wall's light
// reflected by the floor (and the floor's by the wall) is the indirect layer; the splat's mean
// agrees with the path tracer's.
TEST(Environment, SkyPhotonsGiveThePathTracersIndirectLight) {
    Scene s;
    s.path = "corner under the sky";
    uint32_t white = addMaterial(s, MaterialKind::Lambert, Vec3(0.7f));
    addQuad(s, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, white);
    addQuad(s, {-2, 0, -2}, {2, 0, -2}, {2, 2, -2}, {-2, 2, -2}, white);
    s.cameras.push_back(lookAt({0, 1.2f, 2.5f}, {0, 0.5f, -2}, {0, 1, 0}, 0.9f));
    s.computeBounds();
    TempDir dir;
    std::vector<Vec3> px;
    patchedSky(&px);
    RenderConfig cfg = envConfig(32);
    cfg.env = writeEnvironment(dir, px, 64, 32);
    cfg.passes = 4;
    const RenderResult splat = render(s, cfg, silentReporter());
    cfg.method = Method::Path;
    cfg.spp = 512;
    cfg.passes = 1;
    const RenderResult path = render(s, cfg, silentReporter());
    const double ratio = layerMean(splat.film, kIndirect) / layerMean(path.film, kIndirect);
    RecordProperty("indirect_ratio", std::to_string(ratio));
    EXPECT_NEAR(ratio, 1.0, 0.03);
    EXPECT_NEAR(layerMean(splat.film, kDirect) / layerMean(path.film, kDirect), 1.0, 0.02);
}

// A closed room lit by the sun and a sky through one window of a twelfth of its wall: without
// portals most photons land on the roof and the outer walls; with the window as a portal every
// photon path starts through it. The light inside is the same: both splats' indirect light
// agrees with the path tracer's.
TEST(Portals, SunAndSkyPhotonsEnterThroughTheWindow) {
    Scene s;
    s.path = "room with a window";
    uint32_t white = addMaterial(s, MaterialKind::Lambert, Vec3(0.7f));
    // Inward-facing walls of x, z in [-2, 2], y in [0, 3]; the +X wall has a 1 m window.
    addQuad(s, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, white);   // floor
    addQuad(s, {-2, 3, -2}, {2, 3, -2}, {2, 3, 2}, {-2, 3, 2}, white);   // ceiling
    addQuad(s, {-2, 0, -2}, {2, 0, -2}, {2, 3, -2}, {-2, 3, -2}, white); // back, −Z
    addQuad(s, {-2, 0, 2}, {-2, 3, 2}, {2, 3, 2}, {2, 0, 2}, white);     // front, +Z
    addQuad(s, {-2, 0, -2}, {-2, 3, -2}, {-2, 3, 2}, {-2, 0, 2}, white); // −X
    const float y0 = 1.f, y1 = 2.f, z0 = -0.5f, z1 = 0.5f;
    addQuad(s, {2, 0, -2}, {2, 0, 2}, {2, y0, 2}, {2, y0, -2}, white);   // +X below the window
    addQuad(s, {2, y1, -2}, {2, y1, 2}, {2, 3, 2}, {2, 3, -2}, white);   // above
    addQuad(s, {2, y0, -2}, {2, y0, z0}, {2, y1, z0}, {2, y1, -2}, white);
    addQuad(s, {2, y0, z1}, {2, y0, 2}, {2, y1, 2}, {2, y1, z1}, white);
    PunctualLight sun;
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(Vec3(-1.f, -0.7f, 0.15f));
    sun.intensity = Vec3(6.f, 5.5f, 5.f);
    s.lights.push_back(sun);
    s.cameras.push_back(lookAt({-1.6f, 1.6f, 1.6f}, {0.6f, 0.3f, -0.2f}, {0, 1, 0}, 1.1f));
    s.computeBounds();
    Scene withPortal = s;
    withPortal.portals = {{2, y0, z0}, {2, y0, z1}, {2, y1, z1}, {2, y0, z0}, {2, y1, z1}, {2, y1, z0}};
    withPortal.computeBounds();

    RenderConfig cfg = envConfig(24);
    cfg.sky = Vec3(0.6f, 0.7f, 0.9f);
    cfg.passes = 4;
    const RenderResult none = render(s, cfg, silentReporter());
    const RenderResult portal = expectSamePixelsWhateverTheThreadCount(withPortal, cfg);
    cfg.method = Method::Path;
    cfg.spp = 1024;
    cfg.passes = 1;
    const RenderResult path = render(s, cfg, silentReporter());
    const double pathsNone = none.stats.count("photon_paths"), pathsPortal = portal.stats.count("photon_paths");
    RecordProperty("photon_paths_without_portal", std::to_string(pathsNone));
    RecordProperty("photon_paths_with_portal", std::to_string(pathsPortal));
    EXPECT_LT(pathsPortal * 4.0, pathsNone);
    const double ref = layerMean(path.film, kIndirect);
    RecordProperty("indirect_ratio_without_portal", std::to_string(layerMean(none.film, kIndirect) / ref));
    RecordProperty("indirect_ratio_with_portal", std::to_string(layerMean(portal.film, kIndirect) / ref));
    EXPECT_NEAR(layerMean(none.film, kIndirect) / ref, 1.0, 0.04);
    EXPECT_NEAR(layerMean(portal.film, kIndirect) / ref, 1.0, 0.04);
    EXPECT_NEAR(layerMean(portal.film, kDirect) / layerMean(path.film, kDirect), 1.0, 0.03);
}

// data/daylight.gltf: of the photons a pass stores with the window as a portal, at least 80 %
// land inside the room (reaching their hit point from within its walls or the window's
// reveal); without the portal most land outside.
TEST(Portals, DaylightPhotonsLandInsideTheRoom) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    Scene scene = loadScene(std::string(data) + "/daylight.gltf", silentReporter());
    ASSERT_FALSE(scene.portals.empty());
    RenderConfig cfg;
    const Environment env = cfg.environment(scene);
    ASSERT_FALSE(env.black());
    ThreadPool pool(2);
    auto insideShare = [&](const Scene& s) {
        RayAccel accel(s, pool.size());
        LightSampler lights(s, &env);
        PhotonSettings ps;
        ps.split = cfg.photonSplit();
        ps.photons = 40000;
        const PhotonMap map = tracePhotons(s, accel, lights, ps, pool, silentReporter());
        int64_t inside = 0;
        for (const PhotonRay& r : map.rays) {
            // Just before the hit: in the room, or in the window's reveal (walls are single quads,
            // so a hit on a wall's outside lies on the room's bounds too).
            const Vec3 x = r.origin + (r.length - 1e-3f) * r.dir;
            const bool room = x.x > -2.5f && x.x < 2.5f && x.y > 0.f && x.y < 2.7f && x.z > -2.f && x.z < 2.f;
            const bool reveal = x.x > -2.75f && x.x <= -2.5f && x.y > 0.9f && x.y < 1.9f && x.z > -0.9f && x.z < 0.1f;
            inside += room || reveal;
        }
        return double(inside) / double(map.rays.size());
    };
    const double withPortal = insideShare(scene);
    scene.portals.clear();
    const double without = insideShare(scene);
    RecordProperty("inside_with_portal", std::to_string(withPortal));
    RecordProperty("inside_without_portal", std::to_string(without));
    EXPECT_GE(withPortal, 0.8);
    EXPECT_LT(without, withPortal);
}

// A white furnace: a cup open to a uniform sky (a box without its top, albedo 1, seen from above
// and from the side) reflects exactly the sky's radiance L everywhere, after however many
// bounces; the camera sees L where it sees the sky too. Splat (photons from the sky for the
// bounces) and path tracer alike.
TEST(Environment, WhiteFurnaceUnderAUniformSky) {
    Scene s;
    s.path = "white cup";
    const uint32_t white = addMaterial(s, MaterialKind::Lambert, Vec3(1.f));
    addQuad(s, {-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}, white);   // bottom, inside face up
    addQuad(s, {-1, 0, -1}, {-1, 0, 1}, {-1, 1, 1}, {-1, 1, -1}, white);
    addQuad(s, {1, 0, -1}, {1, 1, -1}, {1, 1, 1}, {1, 0, 1}, white);
    addQuad(s, {-1, 0, -1}, {-1, 1, -1}, {1, 1, -1}, {1, 0, -1}, white);
    addQuad(s, {-1, 0, 1}, {1, 0, 1}, {1, 1, 1}, {-1, 1, 1}, white);
    s.cameras.push_back(lookAt({0.4f, 2.6f, 1.9f}, {0, 0.3f, 0}, {0, 1, 0}, 1.0f));
    s.computeBounds();
    RenderConfig cfg = envConfig(24);
    cfg.sky = Vec3(0.8f);
    cfg.passes = 4;
    cfg.maxDepth = 64;
    const RenderResult splat = render(s, cfg, silentReporter());
    cfg.method = Method::Path;
    cfg.spp = 256;
    cfg.passes = 1;
    const RenderResult path = render(s, cfg, silentReporter());
    for (const RenderResult* r : {&splat, &path}) {
        const std::vector<Vec3> beauty = r->film.beautyImage();
        DVec3 sum(0.0);
        for (const Vec3& v : beauty) sum += DVec3(v);
        sum /= double(beauty.size());
        EXPECT_NEAR(sum.x, 0.8, 0.8 * 0.03) << (r == &splat ? "splat" : "path");
    }
}

// The sun alone through a 1 m window of a closed room: on the floor the patch the window's
// outline casts along the sun has radiance ρ/π·E·cos θ, outside it nothing direct. Pixels seen
// well inside and well outside the patch, from above through a hole in the ceiling.
TEST(Environment, SunPatchThroughAnOpeningIsAnalytic) {
    Scene s;
    s.path = "sun through a window";
    const uint32_t grey = addMaterial(s, MaterialKind::Lambert, Vec3(0.5f));
    // Room x, z in [-2, 2], y in [0, 2]; the window in the +X wall: y in [1, 1.6], z in [-0.3, 0.3].
    addQuad(s, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, grey);
    addQuad(s, {-2, 0, -2}, {2, 0, -2}, {2, 2, -2}, {-2, 2, -2}, grey);
    addQuad(s, {-2, 0, 2}, {-2, 2, 2}, {2, 2, 2}, {2, 0, 2}, grey);
    addQuad(s, {-2, 0, -2}, {-2, 2, -2}, {-2, 2, 2}, {-2, 0, 2}, grey);
    addQuad(s, {-2, 2, -2}, {2, 2, -2}, {2, 2, 2}, {-2, 2, 2}, grey);  // ceiling
    addQuad(s, {2, 0, -2}, {2, 0, 2}, {2, 1, 2}, {2, 1, -2}, grey);
    addQuad(s, {2, 1.6f, -2}, {2, 1.6f, 2}, {2, 2, 2}, {2, 2, -2}, grey);
    addQuad(s, {2, 1, -2}, {2, 1, -0.3f}, {2, 1.6f, -0.3f}, {2, 1.6f, -2}, grey);
    addQuad(s, {2, 1, 0.3f}, {2, 1, 2}, {2, 1.6f, 2}, {2, 1.6f, 0.3f}, grey);
    PunctualLight sun;
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(Vec3(-1.f, -1.f, 0.f));  // 45°: the patch is x in [0.4, 1], z in [-0.3, 0.3]
    sun.intensity = Vec3(4.f);
    s.lights.push_back(sun);
    s.portals = {{2, 1, -0.3f}, {2, 1, 0.3f}, {2, 1.6f, 0.3f}, {2, 1, -0.3f}, {2, 1.6f, 0.3f}, {2, 1.6f, -0.3f}};
    // From straight above, inside the room, looking down at x in [0.2, 1.2], z in [-0.5, 0.5].
    Camera c;
    c.position = {0.7f, 1.9f, 0.f};
    c.forward = {0, -1, 0};
    c.up = {-1, 0, 0};
    c.right = glm::cross(c.forward, c.up);
    c.yfov = 2.f * std::atan(0.5f / 1.9f);
    c.aspect = 1.f;
    s.cameras.push_back(c);
    s.computeBounds();
    const double want = 0.5 / kPi * 4.0 * std::cos(kPi / 4);
    for (Method m : {Method::Splat, Method::Path}) {
        RenderConfig cfg = envConfig(40);
        cfg.method = m;
        cfg.spp = m == Method::Path ? 16 : 0;
        cfg.passes = 1;
        const RenderResult r = render(s, cfg, silentReporter());
        DVec3 in(0.0), out(0.0);
        int nIn = 0, nOut = 0;
        for (int y = 0; y < 40; ++y)
            for (int x = 0; x < 40; ++x) {
                // Pixel centre → floor point: the camera's right is −Z... up is −X.
                const double fx = 0.7 - (0.5 - (y + 0.5) / 40.0) * 1.0, fz = ((x + 0.5) / 40.0 - 0.5) * 1.0;
                const Vec3 v = r.film.layers[kDirect][size_t(y) * 40 + x];
                const bool inside = fx > 0.45 && fx < 0.95 && std::abs(fz) < 0.25;
                const bool outside = (fx < 0.35 || fx > 1.05) || std::abs(fz) > 0.35;
                if (inside) in += DVec3(v), ++nIn;
                if (outside) out += DVec3(v), ++nOut;
            }
        ASSERT_GT(nIn, 50);
        ASSERT_GT(nOut, 50);
        EXPECT_NEAR(in.x / nIn, want, 0.01 * want) << methodName(m);
        EXPECT_LT(out.x / nOut, 1e-4) << methodName(m);
    }
}

namespace {

// A Radiance picture of w × h pixels, top row first: flat scanlines when `runLength` is false,
// else the run-length scanlines of Radiance's newer format (a run for each channel's row).
std::string writeRadiance(const TempDir& dir, const std::vector<std::array<uint8_t, 4>>& rgbe, int w, int h, bool runLength) {
    const std::string path = (dir.path() / (runLength ? "sky_rle.hdr" : "sky.hdr")).string();
    std::ofstream out(path, std::ios::binary);
    out << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y " << h << " +X " << w << "\n";
    for (int y = 0; y < h; ++y) {
        if (!runLength) {
            for (int x = 0; x < w; ++x) out.write(reinterpret_cast<const char*>(rgbe[size_t(y) * w + x].data()), 4);
            continue;
        }
        const uint8_t head[4] = {2, 2, uint8_t(w >> 8), uint8_t(w & 0xff)};
        out.write(reinterpret_cast<const char*>(head), 4);
        for (int c = 0; c < 4; ++c)  // literal runs of at most 128 bytes
            for (int x0 = 0; x0 < w; x0 += 128) {
                const int n = std::min(128, w - x0);
                out.put(char(n));
                for (int x = x0; x < x0 + n; ++x) out.put(char(rgbe[size_t(y) * w + x][c]));
            }
    }
    return path;
}

}  // namespace

// --env reads a Radiance .hdr as it reads an OpenEXR: the same radiance in every pixel, flat
// and run-length scanlines alike (RGBE values chosen exact in both: r·2^(e−136)).
TEST(Environment, RadianceHdrReadsAsTheSameExr) {
    TempDir dir;
    const int w = 16, h = 8;
    std::vector<std::array<uint8_t, 4>> rgbe(size_t(w) * h);
    std::vector<Vec3> px(rgbe.size());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const uint8_t r = uint8_t(128 + 8 * x % 128), g = uint8_t(128 + 16 * y), b = 200, e = uint8_t(129 + (x + y) % 3);
            rgbe[size_t(y) * w + x] = {r, g, b, e};
            const float scale = std::ldexp(1.f, int(e) - 136);
            px[size_t(y) * w + x] = Vec3(r * scale, g * scale, b * scale);
        }
    const Environment fromExr = loadEnvironment(writeEnvironment(dir, px, w, h), 1.5f, 0.3f);
    for (bool runLength : {false, true}) {
        const Environment fromHdr = loadEnvironment(writeRadiance(dir, rgbe, w, h, runLength), 1.5f, 0.3f);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const Vec3 d = blenderDirection((x + 0.5f) / w, (y + 0.5f) / h);
                EXPECT_EQ(fromHdr.radiance(d), fromExr.radiance(d)) << "pixel " << x << "," << y << (runLength ? " (RLE)" : "");
            }
        EXPECT_EQ(fromHdr.integral(), fromExr.integral());
    }
    // A file that begins as a Radiance picture and breaks off is one error naming it.
    const std::string broken = (dir.path() / "broken.hdr").string();
    std::ofstream(broken, std::ios::binary) << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8 +X 16\n\x02\x02";
    try {
        loadEnvironment(broken, 1.f, 0.f);
        ADD_FAILURE() << "a broken .hdr was read";
    } catch (const rs::Error& e) {
        EXPECT_NE(std::string(e.what()).find(broken), std::string::npos) << e.what();
    }
}
