// Light does not leak through walls: a photon segment lights no eye sample it cannot see,
// nothing behind the surface it leaves and nothing behind the surface it ends on, whatever
// the grid and the kernel radius. Each cause found in the splat of the paper's method has a
// single-photon test here (each lit the sample before the receiver rules), then whole
// renders check the rules end to end: a sealed room next to a lit one stays black, a room
// split by a thin slab keeps its dark half dark.
#include <gtest/gtest.h>

#include <cstdlib>

#include "scene/accel.h"
#include "splat/eye.h"
#include "occlusion/kdtree.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/sampling.h"
#include "splat/photons.h"
#include "render.h"
#include "splat/splat.h"
#include "test_scenes.h"
#include "grid/voxelize.h"

using namespace rs;
using namespace rs::test;

namespace {

// ---- One photon segment against hand-placed eye samples -------------------------------

// A wall 8 cm thick (x in [−0.04, 0.04]) standing on a floor that runs under both sides:
// the lit side is x > 0.04, the dark side x < −0.04.
struct WallScene {
    Scene scene;
    uint32_t white = 0;
    WallScene() {
        white = addMaterial(scene, MaterialKind::Lambert, Vec3(0.5f));
        addBox(scene, {-0.04f, 0.f, -1.f}, {0.04f, 2.f, 1.f}, white);
        addQuad(scene, {-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}, white);
        scene.computeBounds();
    }
};

// Eye samples at the given points (normal = the side they are seen from), one film pixel
// each; returns the light each pixel received from the one photon segment.
std::vector<float> splatOne(const WallScene& w, const PhotonRay& ray, const std::vector<std::pair<Vec3, Vec3>>& at,
                            int grid) {
    ThreadPool pool(1);
    RayAccel accel(w.scene, 1);
    OcclusionGrid occ = voxelizeCpu(w.scene, gridForBounds(w.scene.bounds, grid), pool, silentReporter());
    EyeSamples eye;
    for (size_t i = 0; i < at.size(); ++i) {
        const Vec3 f = w.scene.materials[w.white].baseColor * kInvPi;  // Lambert, weight 1
        eye.add(at[i].first, at[i].second, at[i].second, false, uint32_t(i), f);
    }
    OcclusionTree tree = buildOcclusionTree(occ, eye, pool);  // reorders eye, pixels stay
    PhotonMap map;
    map.rays.push_back(ray);
    FixedFilm sum(int(at.size()), 1);
    splatPhotons(accel, tree, eye, map, SplatSettings(), sum, pool, silentReporter());
    const Film film = sum.average(1);
    std::vector<float> got;
    for (size_t i = 0; i < at.size(); ++i) got.push_back(film.layers[ray.cls][i].x);
    return got;
}

PhotonRay segment(Vec3 from, Vec3 to, float radius, Vec3 originNormal = Vec3(0.f)) {
    PhotonRay r{};
    r.origin = from;
    r.dir = glm::normalize(to - from);
    r.length = glm::length(to - from);
    r.radius = radius;
    r.reach = 16.f;  // the longest overrun past the end: the hardest case for the rules
    r.flux = Vec3(1.f);
    r.originNormal = glm::dot(originNormal, originNormal) > 0.f ? encodeUnit(originNormal) : 0u;
    r.cls = kPhotonIndirect;
    return r;
}

const Vec3 kUp(0, 1, 0), kLitSide(1, 0, 0), kDarkSide(-1, 0, 0);

}  // namespace

// Cause 1: a photon leaving the lit face at a grazing angle reaches the dark face, which is
// behind the surface it leaves; the mask skips every voxel behind that surface (so as not
// to shadow the photon's own origin), so nothing stopped it.
TEST(LeakCause, NothingReachesBehindTheSurfaceASegmentLeaves) {
    WallScene w;
    PhotonRay r = segment({0.0401f, 1.2f, 0.f}, {0.30f, 0.f, 0.f}, 0.25f, kLitSide);
    for (int grid : {64, 192}) {
        std::vector<float> got = splatOne(w, r, {{{-0.04f, 0.7f, 0.f}, kDarkSide},      // the dark face
                                                 {{0.25f, 0.f, 0.05f}, kUp}}, grid);    // the lit floor
        EXPECT_EQ(got[0], 0.f) << "grid " << grid;
        EXPECT_GT(got[1], 0.f) << "grid " << grid << ": the lit floor under the segment receives";
    }
}

// Cause 2: a segment ending on the lit face at a grazing angle; its kernel runs on past the
// hit (about h) onto the dark floor behind the wall. The mask counts only the wall's
// back-facing side, and the occlusion sums of a face seen at a grazing angle fall short of
// full.
TEST(LeakCause, NothingReachesBehindTheSurfaceASegmentEndsOn) {
    WallScene w;
    PhotonRay r = segment({0.3f, 1.8f, 0.f}, {0.04f, 0.15f, 0.f}, 0.3f, -kUp);  // from a ceiling
    for (int grid : {64, 192}) {
        std::vector<float> got = splatOne(w, r, {{{-0.12f, 0.f, 0.f}, kUp},            // dark floor past the end
                                                 {{0.20f, 0.f, 0.02f}, kUp}}, grid);    // lit floor below the end
        EXPECT_EQ(got[0], 0.f) << "grid " << grid;
        EXPECT_GT(got[1], 0.f) << "grid " << grid;
    }
}

// Cause 3: a segment running down the lit side of the wall, parallel to it. The dark floor
// next to the wall lies within the kernel, and the parallel ray through it runs down the
// dark side: the mask, which looks along the segment's direction only, sees no wall.
TEST(LeakCause, NothingReachesPastAWallBesideTheSegment) {
    WallScene w;
    PhotonRay r = segment({0.12f, 1.9f, 0.f}, {0.12f, 0.f, 0.f}, 0.3f);
    for (int grid : {64, 192}) {
        std::vector<float> got = splatOne(w, r, {{{-0.10f, 0.f, 0.05f}, kUp},           // dark floor
                                                 {{0.20f, 0.f, 0.05f}, kUp}}, grid);    // lit floor
        EXPECT_EQ(got[0], 0.f) << "grid " << grid;
        EXPECT_GT(got[1], 0.f) << "grid " << grid;
    }
}

// The rules take nothing the segment can light: around a segment that ends on an open
// floor every sample under the kernel receives, and the sum over a dense lattice of
// samples is the photon's flux × ρ/π (the kernel integrates to one).
TEST(LeakCause, OpenFloorKeepsEveryContribution) {
    WallScene w;
    PhotonRay r = segment({0.6f, 1.0f, 0.3f}, {0.5f, 0.f, 0.2f}, 0.15f, Vec3(0.f));
    std::vector<std::pair<Vec3, Vec3>> at;
    const int n = 60;
    const float side = 0.4f, da = sqr(side / n);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            at.push_back({{0.3f + (i + 0.5f) * side / n, 0.f, (j + 0.5f) * side / n}, kUp});
    std::vector<float> got = splatOne(w, r, at, 128);
    double sum = 0.0;
    for (float v : got) sum += double(v) * da;
    EXPECT_NEAR(sum * kPi / 0.5, 1.0, 0.02);
}

// ---- Whole renders ----------------------------------------------------------------------

namespace {

RenderConfig roomConfig(int grid, const std::string& camera, Visibility visibility = Visibility::Auto) {
    RenderConfig cfg;
    cfg.visibility = visibility;
    cfg.output = "unused.exr";
    cfg.width = 40;
    cfg.height = 30;
    cfg.photons = 20000;
    cfg.grid = grid;
    cfg.voxelizer = "cpu";
    cfg.camera = camera;
    cfg.passes = 1;
    return cfg;
}

}  // namespace

// Two rooms sharing an 8 cm wall (2.5 voxels at grid 192), the light in one, the camera in
// the other: the dark room's image is black — below 1e-4 of the lit room's mean in every
// layer (direct, indirect, caustic from the glass ball beside the wall) — with the mask at every
// grid, and with visibility by rays (whose kernels reach on to the scene's bounds, through the
// wall: only rule 2 stops them) at the default grid.
TEST(SealedRooms, DarkRoomStaysBlackAtEveryGrid) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    Scene scene = loadScene(std::string(data) + "/two_rooms_sealed.gltf", silentReporter());
    for (auto [grid, visibility] : {std::pair{96, Visibility::Mask}, {192, Visibility::Mask}, {384, Visibility::Mask},
                                    {192, Visibility::Rays}}) {
        RenderResult dark = render(scene, roomConfig(grid, "camera", visibility), silentReporter());
        RenderResult lit = render(scene, roomConfig(grid, "lit_camera", visibility), silentReporter());
        for (int layer : {kDirect, kIndirect, kCaustic}) {
            double litMean = layerMean(lit.film, layer), darkMean = layerMean(dark.film, layer);
            const std::string where = std::string(layerName(layer)) + " at grid " + std::to_string(grid) + ", " +
                                      visibilityName(visibility);
            EXPECT_GT(litMean, 0.0) << where;
            EXPECT_LT(darkMean, 1e-4 * litMean) << where;
        }
    }
}

// The sealed rooms with a bumpy normal map on every surface (16 × 16 texels tilted up to 60°
// in random directions, 4 texels a metre, tangents computed): shading normals that lean
// through the wall must not let light through it. The dark room stays black as without the
// map, at the default grid with the mask and with rays.
TEST(SealedRooms, NormalMappedWallsKeepTheDarkRoomBlack) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    Scene scene = loadScene(std::string(data) + "/two_rooms_sealed.gltf", silentReporter());
    const RenderResult flat = render(scene, roomConfig(192, "lit_camera", Visibility::Mask), silentReporter());
    std::vector<Vec4> bumps;
    uint64_t h = 7;
    for (int i = 0; i < 16 * 16; ++i) {
        h = mix64(h + 1);
        const float phi = 2.f * kPi * toUnitFloat(uint32_t(h)), theta = 1.047f * toUnitFloat(uint32_t(h >> 32));
        const Vec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
        bumps.push_back(Vec4(0.5f * n + 0.5f, 1.f));
    }
    const int tex = addTexture(scene, 16, 16, bumps);
    for (Material& m : scene.materials) m.normalTexture.texture = tex;
    for (size_t c = 0; c < scene.positions.size(); ++c) {
        // Planar uvs across the triangle's dominant axis, so that every wall has a frame.
        const Vec3 n = glm::abs(scene.geometricNormal(c / 3)), p = scene.positions[c] * 0.25f;
        scene.uvs[c] = n.x > n.y && n.x > n.z ? Vec2(p.y, p.z) : n.y > n.z ? Vec2(p.x, p.z) : Vec2(p.x, p.y);
    }
    scene.tangents.assign(scene.positions.size(), Vec4(0.f));
    computeMissingTangents(scene);
    for (Visibility visibility : {Visibility::Mask, Visibility::Rays}) {
        RenderResult dark = render(scene, roomConfig(192, "camera", visibility), silentReporter());
        RenderResult lit = render(scene, roomConfig(192, "lit_camera", visibility), silentReporter());
        for (int layer : {kDirect, kIndirect, kCaustic}) {
            double litMean = layerMean(lit.film, layer), darkMean = layerMean(dark.film, layer);
            const std::string where = std::string(layerName(layer)) + ", " + visibilityName(visibility);
            EXPECT_GT(litMean, 0.0) << where;
            EXPECT_LT(darkMean, 1e-4 * litMean) << where;
        }
        if (visibility != Visibility::Mask) continue;
        // The map is there: the lit room's pixels differ from the flat walls'.
        double change = 0.0;
        for (size_t p = 0; p < lit.film.pixelCount(); ++p)
            change += glm::length(lit.film.layers[kDirect][p] - flat.film.layers[kDirect][p]);
        EXPECT_GT(change / double(lit.film.pixelCount()), 0.05 * layerMean(flat.film, kDirect));
    }
}

// The same rooms joined by a 25 cm opening: light reaches the camera's room only through
// it. Each layer's mean is within 5 % of the path tracer's (before the receiver rules the
// indirect layer was 2.5× too bright). Kernels of 1–4 voxels at grid 384 keep the density
// estimate's own blur small against the opening (measured with the default visibility by
// rays: direct −0.3 %, indirect +0.1 %; with the mask at 384 indirect was −2.0 %). The caustic
// layer holds almost nothing here (the glass ball is in the other room) and is left out.
TEST(GapRooms, LayersMatchThePathTracerThroughTheOpening) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    Scene scene = loadScene(std::string(data) + "/two_rooms_gap.gltf", silentReporter());
    RenderConfig cfg = roomConfig(384, "camera");
    cfg.width = 64;
    cfg.height = 48;
    cfg.photons = 400000;
    cfg.spp = 8;
    cfg.lightSamples = 4;
    for (int c = 0; c < 3; ++c) cfg.minRadius[c] = 1.f, cfg.maxRadius[c] = 4.f;
    RenderResult splat = render(scene, cfg, silentReporter());
    cfg.method = Method::Path;
    cfg.spp = 2048;
    RenderResult path = render(scene, cfg, silentReporter());
    for (int layer : {kDirect, kIndirect}) {
        double got = layerMean(splat.film, layer), want = layerMean(path.film, layer);
        RecordProperty(std::string(layerName(layer)) + "_ratio", std::to_string(got / want));
        EXPECT_NEAR(got / want, 1.0, 0.05) << layerName(layer);
    }
}

namespace {

// A closed 2 × 1 × 1 m box split at x = 0 by a slab `thickness` thick, a point light in the
// left half; cameras in each half look at the slab.
Scene splitBox(float thickness, Vec3 light) {
    Scene s;
    uint32_t white = addMaterial(s, MaterialKind::Lambert, Vec3(0.6f));
    addBox(s, {-1, 0, 0}, {1, 1, 1}, white, /*inward=*/true);
    addBox(s, {-thickness / 2, 0, 0}, {thickness / 2, 1, 1}, white);
    PunctualLight l;
    l.position = light;
    l.intensity = Vec3(2.f);
    s.lights.push_back(l);
    for (float side : {-1.f, 1.f}) {
        Camera c;
        c.name = side < 0 ? "lit" : "dark";
        c.position = {0.85f * side, 0.5f, 0.5f};
        c.forward = {-side, 0.f, 0.f};
        c.up = {0.f, 1.f, 0.f};
        c.right = glm::cross(c.forward, c.up);
        c.yfov = 1.6f;
        c.aspect = 1.f;
        s.cameras.push_back(c);
    }
    s.computeBounds();
    return s;
}

}  // namespace

// A slab 1.5 voxels thick lit from one side, the light square in front of it and grazing
// along it: the unlit half receives under 1 % of the lit half's light, with either visibility.
TEST(ThinSlab, UnlitSideStaysDarkAtNormalAndGrazingIncidence) {
    const int grid = 64;
    const float voxel = 2.04f / grid;  // the box's 2 m, padded by a voxel on each side
    for (Vec3 light : {Vec3(-0.5f, 0.5f, 0.5f), Vec3(-0.03f, 0.95f, 0.5f)})
    for (Visibility visibility : {Visibility::Mask, Visibility::Rays}) {
        Scene s = splitBox(1.5f * voxel, light);
        RenderConfig cfg = roomConfig(grid, "lit", visibility);
        RenderResult lit = render(s, cfg, silentReporter());
        cfg.camera = "dark";
        RenderResult dark = render(s, cfg, silentReporter());
        double litMean = layerMean(lit.film, kDirect) + layerMean(lit.film, kIndirect);
        double darkMean = layerMean(dark.film, kDirect) + layerMean(dark.film, kIndirect);
        EXPECT_GT(litMean, 0.0);
        EXPECT_LT(darkMean, 0.01 * litMean) << "light at " << light.x << ", " << light.y << ", " << visibilityName(visibility);
    }
}
