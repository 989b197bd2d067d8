// The ray-splat renderer end to end and its splat stage, against independent answers:
// analytic irradiance, the reference path tracer, and energy conservation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <set>

#include "splat/eye.h"
#include "splat/irradiance.h"
#include "occlusion/kdtree.h"
#include "scene/lights.h"
#include "core/log.h"
#include "core/parallel.h"
#include "splat/photons.h"
#include "render.h"
#include "splat_pass.h"
#include "splat/kernel_scale.h"
#include "splat/splat.h"
#include "splat/targets.h"
#include "scene/triangle_bvh.h"
#include "test_scenes.h"
#include "grid/voxelize.h"

using namespace rs;
using namespace rs::test;

namespace {

// A 4 m diffuse floor lit by a point light 1.5 m above it, seen from above.
Scene litFloor(bool occluder) {
    Scene s;
    uint32_t floor = addMaterial(s, MaterialKind::Lambert, Vec3(0.5f));
    addQuad(s, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, floor);
    if (occluder) addBox(s, {-0.3f, 0.5f, -0.3f}, {0.3f, 0.6f, 0.3f}, floor);
    PunctualLight l;
    l.position = occluder ? Vec3(1.2f, 1.5f, 0.f) : Vec3(0.f, 1.5f, 0.f);  // the shadow beside the slab
    l.intensity = Vec3(4.f);
    s.lights.push_back(l);
    Camera c;
    c.position = {0.f, 3.f, 0.f};
    c.forward = {0.f, -1.f, 0.f};
    c.up = {0.f, 0.f, -1.f};
    c.right = glm::cross(c.forward, c.up);
    c.yfov = 1.2f;  // the floor from x = −2.05 to 2.05 in view
    c.aspect = 1.f;
    s.cameras.push_back(c);
    s.computeBounds();
    return s;
}

RenderConfig splatConfig(int width, Method method = Method::Splat) {
    RenderConfig cfg;
    cfg.output = "unused.exr";
    cfg.method = method;
    cfg.width = width;
    cfg.height = width;
    cfg.spp = 4;
    cfg.grid = 96;
    cfg.voxelizer = "cpu";
    cfg.passes = 1;
    return cfg;
}

// Where pixel (x, y) of litFloor's camera looks at the floor (pixel centre).
Vec3 floorPoint(const Camera& c, int width, int x, int y) {
    float t = std::tan(0.5f * c.yfov);
    float sx = (2.f * (x + 0.5f) / width - 1.f) * t, sy = (1.f - 2.f * (y + 0.5f) / width) * t;
    Vec3 d = glm::normalize(c.forward + sx * c.right + sy * c.up);
    return c.position + d * (c.position.y / -d.y);
}

}  // namespace

// The splatted direct light on a diffuse floor matches L = ρ/π · I cosθ / r², on average over
// the interior within 3 %, and pixel by pixel within the kernel's noise.
TEST(SplatRenderer, PointLightIrradianceOnDiffusePlane) {
    Scene s = litFloor(false);
    RenderConfig cfg = splatConfig(48);
    cfg.photons = 200000;
    cfg.direct = DirectMethod::Photons;  // the paper's direct light, from photons
    cfg.split[0] = 1.f, cfg.split[1] = 0.f, cfg.split[2] = 0.f;
    cfg.splitSet = true;
    RenderResult r = render(s, cfg, silentReporter());
    double sumRatio = 0.0, sumSqErr = 0.0;
    int n = 0;
    for (int y = 8; y < 40; ++y) {
        for (int x = 8; x < 40; ++x) {
            Vec3 p = floorPoint(s.cameras[0], 48, x, y);
            Vec3 d = s.lights[0].position - p;
            float r2 = glm::dot(d, d);
            float expected = 0.5f / kPi * 4.f * (d.y / std::sqrt(r2)) / r2;
            float got = r.film.layers[kDirect][size_t(y) * 48 + x].x;
            sumRatio += got / expected;
            sumSqErr += sqr(got / expected - 1.f);
            ++n;
        }
    }
    EXPECT_NEAR(sumRatio / n, 1.0, 0.03);
    EXPECT_LT(std::sqrt(sumSqErr / n), 0.15);  // per-pixel relative RMS error
}

// A hard shadow beside a small slab: right next to the shadow's edge the splat keeps the
// floor dark like the path tracer; splatting without visibility (the paper's Fig. 4b) spreads
// the lit side's photons over the edge into the shadow.
TEST(SplatRenderer, ShadowEdgeStaysSharpButLeaksWithoutVisibility) {
    Scene s = litFloor(true);
    const int w = 96;
    RenderConfig cfg = splatConfig(w);
    cfg.grid = 128;
    cfg.photons = 100000;
    cfg.direct = DirectMethod::Photons;  // the paper's direct light, from photons
    cfg.split[0] = 1.f, cfg.split[1] = 0.f, cfg.split[2] = 0.f;
    cfg.splitSet = true;
    cfg.kernelPhotons[0] = 256.f;  // a wide kernel: h ≈ 0.25 m, six pixels
    RenderResult splat = render(s, cfg, silentReporter());
    cfg.method = Method::SplatNoVis;
    RenderResult novis = render(s, cfg, silentReporter());
    cfg.method = Method::Path;
    cfg.spp = 16;
    RenderResult path = render(s, cfg, silentReporter());

    // Light at (1.2, 1.5, 0), slab |x|,|z| < 0.3 at y = 0.5…0.6: on the floor the shadow spans
    // x ∈ [−1.3, −0.15] (the far edge from the slab's upper corner), |z| ≲ 0.5 there. The
    // band: x ∈ [−1.27, −1.15] inside the shadow, next to its edge; the lit reference:
    // x ∈ [−1.9, −1.45]; both |z| < 0.25.
    auto inBand = [&](Vec3 p) { return p.x > -1.27f && p.x < -1.15f && std::abs(p.z) < 0.25f; };
    auto lit = [&](Vec3 p) { return p.x > -1.9f && p.x < -1.45f && std::abs(p.z) < 0.25f; };
    double band[3] = {}, litSum[3] = {};
    int nb = 0, nl = 0;
    const RenderResult* results[3] = {&splat, &novis, &path};
    for (int y = 0; y < w; ++y) {
        for (int x = 0; x < w; ++x) {
            Vec3 p = floorPoint(s.cameras[0], w, x, y);
            bool b = inBand(p), l = lit(p);
            if (!b && !l) continue;
            for (int k = 0; k < 3; ++k) (b ? band[k] : litSum[k]) += results[k]->film.layers[kDirect][size_t(y) * w + x].x;
            (b ? nb : nl)++;
        }
    }
    ASSERT_GT(nb, 0);
    ASSERT_GT(nl, 0);
    double contrast[3];  // band radiance relative to the lit floor: 0 for a sharp shadow
    for (int k = 0; k < 3; ++k) contrast[k] = (band[k] / nb) / (litSum[k] / nl);
    RecordProperty("contrast_splat", std::to_string(contrast[0]));
    RecordProperty("contrast_novis", std::to_string(contrast[1]));
    EXPECT_LT(contrast[2], 1e-6) << "the path tracer's shadow is black there";
    EXPECT_LT(contrast[0], 0.05) << "splat keeps the edge of the shadow dark";
    EXPECT_GT(contrast[1], 0.15) << "without visibility light spreads over the edge";
    EXPECT_GT(contrast[1], 5.0 * contrast[0] + 0.1);
}

// Everything that lands on the walls of a closed diffuse room from direct photons, summed
// over eye samples that tile every wall (weight = their area, f_r = ρ/π): ρ·Φ / π.
TEST(SplatStage, ClosedRoomReflectsEmittedPowerTimesAlbedo) {
    const float rho = 0.5f;
    Scene s;
    uint32_t wall = addMaterial(s, MaterialKind::Lambert, Vec3(rho));
    uint32_t light = addMaterial(s, MaterialKind::Lambert, Vec3(0.f), Vec3(10.f));
    addBox(s, {-1, 0, -1}, {1, 2, 1}, wall, /*inward=*/true);
    addQuad(s, {-0.25f, 1.9f, -0.25f}, {0.25f, 1.9f, -0.25f}, {0.25f, 1.9f, 0.25f}, {-0.25f, 1.9f, 0.25f}, light);
    s.computeBounds();
    ThreadPool pool(2);
    RayAccel accel(s, 2);
    LightSampler lights(s);
    OcclusionGrid grid = voxelizeCpu(s, gridForBounds(s.bounds, 64), pool, silentReporter());

    // Eye samples on a 1 cm lattice over the six inner walls.
    EyeSamples eye;
    const int n = 200;
    const float da = sqr(2.f / n);
    for (int axis = 0; axis < 3; ++axis) {
        for (float side : {-1.f, 1.f}) {
            for (int i = 0; i < n; ++i) {
                for (int j = 0; j < n; ++j) {
                    Vec3 p, nrm(0.f);
                    float a = -1.f + (i + 0.5f) * 2.f / n, b = -1.f + (j + 0.5f) * 2.f / n;
                    if (axis == 0) p = {side, 1.f + a, b};
                    else if (axis == 1) p = {a, 1.f + side, b};
                    else p = {a, 1.f + b, side};
                    nrm[axis] = -side;
                    eye.add(p, nrm, nrm, false, 0, da * s.materials[wall].baseColor * kInvPi);  // Lambert
                }
            }
        }
    }
    OcclusionTree tree = buildOcclusionTree(grid, eye, pool);
    PhotonSettings ps;
    ps.photons = 20000;
    ps.split[1] = ps.split[2] = 0.f;
    ps.voxelSize = grid.geometry.voxelSize;
    PhotonMap photons = tracePhotons(s, accel, lights, ps, pool, silentReporter());
    FixedFilm film(1, 1);
    splatPhotons(accel, tree, eye, photons, SplatSettings(), film, pool, silentReporter());
    double reflected = film.average(1).layers[kDirect][0].x * kPi;
    double expected = rho * luminance(s.emittedPower());
    EXPECT_NEAR(reflected / expected, 1.0, 0.05);

    // The ranks of a distributed render splat shares of the photons: three shares add up to
    // the whole, to the bit.
    FixedFilm shared(1, 1);
    for (int share = 0; share < 3; ++share) {
        SplatSettings part;
        part.share = share;
        part.shares = 3;
        FixedFilm one(1, 1);
        splatPhotons(accel, tree, eye, photons, part, one, pool, silentReporter());
        EXPECT_NE(one.buffers[kDirect][0], 0) << "share " << share;
        shared.add(one);
    }
    EXPECT_EQ(shared.buffers[kDirect], film.buffers[kDirect]);
}

// A room with a pillar and a slab in it, and a sphere: enough triangles for the TriangleBvh
// to have levels, and walls that stand beside photon segments.
static Scene furnishedRoom() {
    Scene s;
    uint32_t wall = addMaterial(s, MaterialKind::Lambert, Vec3(0.6f));
    uint32_t light = addMaterial(s, MaterialKind::Lambert, Vec3(0.f), Vec3(10.f));
    addBox(s, {-1, 0, -1}, {1, 2, 1}, wall, /*inward=*/true);
    addBox(s, {-0.2f, 0.f, -0.2f}, {0.2f, 1.4f, 0.2f}, wall);
    addBox(s, {0.3f, 0.6f, -0.8f}, {0.9f, 0.65f, 0.1f}, wall);
    addSphere(s, {-0.5f, 0.4f, 0.5f}, 0.3f, 3, wall);
    addQuad(s, {-0.25f, 1.9f, -0.25f}, {0.25f, 1.9f, -0.25f}, {0.25f, 1.9f, 0.25f}, {-0.25f, 1.9f, 0.25f}, light);
    s.computeBounds();
    return s;
}

// The furnished room's eye samples, size × size pixels, seen from by its door.
static EyePass furnishedRoomEye(const Scene& s, const RayAccel& accel, int size, ThreadPool& pool) {
    Camera c;
    c.position = {0.f, 1.f, 0.95f};
    c.forward = {0.f, 0.f, -1.f};
    c.up = {0.f, 1.f, 0.f};
    c.right = glm::cross(c.forward, c.up);
    c.yfov = 1.4f;
    c.aspect = 1.f;
    EyePassSettings es;
    es.width = es.height = size;
    return traceEyePass(s, accel, nullptr, c, es, pool, silentReporter());
}

// `count` photons in the furnished room, their kernels from a grid of 64 along its diagonal.
static PhotonMap furnishedRoomPhotons(const Scene& s, const RayAccel& accel, int count, ThreadPool& pool) {
    LightSampler lights(s);
    PhotonSettings ps;
    ps.photons = count;
    ps.voxelSize = s.bounds.diagonal() / 64.f;
    return tracePhotons(s, accel, lights, ps, pool, silentReporter());
}

// The BVH's cylinder query finds exactly the triangles whose boxes the cylinder's disc boxes
// touch (brute force over every triangle with the same test), and stops when told to.
TEST(VisibilityPlanes, TriangleBvhFindsWhatBruteForceFinds) {
    const Scene s = furnishedRoom();
    const TriangleBvh bvh(s);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    int nonEmpty = 0;
    for (int q = 0; q < 300; ++q) {
        const Vec3 o(u(rng), 1.f + u(rng), u(rng));
        const Vec3 w = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
        const float r = 0.01f + 0.2f * (u(rng) + 1.f), t1 = 2.f * (u(rng) + 1.f);
        std::set<uint32_t> expected, found;
        float ra[3];
        for (int a = 0; a < 3; ++a) ra[a] = r * std::sqrt(std::max(0.f, 1.f - w[a] * w[a]));
        for (uint32_t t = 0; t < s.triangleCount(); ++t) {
            Bounds3 b;
            for (int k = 0; k < 3; ++k) b.extend(s.positions[3 * t + k]);
            float s0 = 0.f, s1 = t1;
            for (int a = 0; a < 3; ++a) {
                clipLowerFace(o[a], w[a], ra[a], b.lo[a], s0, s1);
                clipUpperFace(o[a], w[a], ra[a], b.hi[a], s0, s1);
            }
            if (s0 <= s1) expected.insert(t);
        }
        EXPECT_TRUE(bvh.nearCylinder(o, w, r, 0.f, t1, [&](uint32_t t) { return found.insert(t).second; }));
        EXPECT_EQ(found, expected) << "query " << q;
        nonEmpty += !expected.empty();
        if (expected.size() > 1) {
            int calls = 0;
            EXPECT_FALSE(bvh.nearCylinder(o, w, r, 0.f, t1, [&](uint32_t) { return ++calls < 2; }));
            EXPECT_EQ(calls, 2);
        }
    }
    EXPECT_GT(nonEmpty, 250);
    EXPECT_LT(bvh.bytes(), s.triangleCount() * 64);
}

// Rule 2 by the triangles never contradicts Embree: a point they call visible from x(i−1) is
// one Embree finds unoccluded (points all over each photon's cylinder, many of them behind
// the pillar or the slab); and the splat gives the same film, to the bit, with the planes and
// with an Embree ray for every receiver, while the planes spare most of those rays; receiving
// four samples at a time gives the same film as one at a time.
TEST(VisibilityPlanes, AgreeWithEmbreeAndLeaveTheImageAsItWas) {
    const Scene s = furnishedRoom();
    ThreadPool pool(2);
    RayAccel accel(s, 2);
    const PhotonMap photons = furnishedRoomPhotons(s, accel, 4000, pool);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    int64_t decided = 0, asked = 0;
    for (const PhotonRay& ray : photons.rays) {
        const SegmentReceivers receivers(accel, ray, true);
        const Frame frame(ray.dir);
        for (int k = 0; k < 16; ++k) {
            const float t = u(rng) * (ray.length + ray.radius * ray.reach), phi = 2.f * kPi * u(rng);
            const float d = ray.radius * std::sqrt(u(rng));
            const Vec3 p = ray.origin + t * ray.dir + frame.toWorld(Vec3(d * std::cos(phi), d * std::sin(phi), 0.f));
            ++asked;
            if (!receivers.surelyVisible(p)) continue;
            ++decided;
            EXPECT_EQ(accel.occludedToPoint(&p, 1, ray.origin), 0u) << "photon at " << ray.origin.x << "," << ray.origin.y << "," << ray.origin.z;
        }
    }
    EXPECT_GT(decided, asked / 10);

    OcclusionGrid grid = voxelizeCpu(s, gridForBounds(s.bounds, 64), pool, silentReporter());
    const int size = 48;
    EyePass eye = furnishedRoomEye(s, accel, size, pool);
    OcclusionTree tree = buildOcclusionTree(grid, eye.samples, pool);
    SplatSettings withPlanes, withRays;
    withRays.visibilityPlanes = false;
    FixedFilm a(size, size), b(size, size);
    SplatStats sa, sb;
    splatPhotons(accel, tree, eye.samples, photons, withPlanes, a, pool, silentReporter(), &sa);
    splatPhotons(accel, tree, eye.samples, photons, withRays, b, pool, silentReporter(), &sb);
    for (int l = 0; l < FixedFilm::kBuffers; ++l) EXPECT_EQ(a.buffers[l], b.buffers[l]) << "buffer " << l;
    EXPECT_EQ(sa.contributions, sb.contributions);
    EXPECT_EQ(sb.visibleByPlanes, 0u);
    // 34 % here (the sphere has many triangles); 14 % by the planes alone, without the edges.
    EXPECT_GT(sa.visibleByPlanes, sa.contributions / 4);
    EXPECT_EQ(sa.visibilityRays + sa.visibleByPlanes, sb.visibilityRays);
    EXPECT_GT(sb.refusedHidden, 0u);

    // Four samples at a time give what one at a time gives, to the bit.
    SplatSettings oneByOne;
    oneByOne.batches = false;
    FixedFilm d(size, size);
    SplatStats sd;
    splatPhotons(accel, tree, eye.samples, photons, oneByOne, d, pool, silentReporter(), &sd);
    for (int l = 0; l < FixedFilm::kBuffers; ++l) EXPECT_EQ(a.buffers[l], d.buffers[l]) << "buffer " << l;
    EXPECT_EQ(sa.contributions, sd.contributions);
    EXPECT_EQ(sa.visibleByPlanes, sd.visibleByPlanes);
    EXPECT_EQ(sa.visibilityRays, sd.visibilityRays);
}

// The sparse receivers found through their CylinderIndex take the light they take when the
// occlusion tree over an empty grid finds them (as it did for them before the index): the same
// receivers' sums to the bit, with the coverage measured for the same photons.
TEST(SparseReceivers, TheIndexGivesTheTreesSums) {
    const Scene s = furnishedRoom();
    ThreadPool pool(2);
    RayAccel accel(s, 2);
    const PhotonMap all = furnishedRoomPhotons(s, accel, 6000, pool);
    PhotonMap indirect;
    for (const PhotonRay& r : all.rays)
        if (r.cls == kPhotonIndirect) indirect.rays.push_back(r);
    ASSERT_GT(indirect.rays.size(), 1000u);
    const EyePass eye = furnishedRoomEye(s, accel, 64, pool);
    const IrradianceReceivers receivers = chooseReceivers(eye.samples, 64, 64, 0.08f, pool);
    ASSERT_LT(receivers.samples.size(), eye.samples.size() / 2);
    const OcclusionGrid empty(gridForBounds(s.bounds, 64));
    EyeSamples ordered = receivers.samples;  // the tree reorders them; a sample's pixel is its slot
    const OcclusionTree tree = buildOcclusionTree(empty, ordered, pool);
    const CylinderIndex index(receivers.samples.position);
    const CoverageSettings coverage;
    SplatSettings byTree;
    byTree.coverage = &coverage;
    byTree.visibilityPlanes = false;
    SplatSettings byIndex = byTree;
    byIndex.index = &index;
    FixedFilm a(int(receivers.slots()), 1), b(int(receivers.slots()), 1);
    SplatStats sa, sb;
    splatPhotons(accel, tree, ordered, indirect, byTree, a, pool, silentReporter(), &sa);
    splatPhotons(accel, tree, receivers.samples, indirect, byIndex, b, pool, silentReporter(), &sb);
    EXPECT_EQ(a.buffers[kIndirect], b.buffers[kIndirect]);
    EXPECT_NE(a.buffers[kIndirect], std::vector<int64_t>(a.buffers[kIndirect].size(), 0));
    EXPECT_EQ(sa.unseen, sb.unseen);
    EXPECT_GT(sb.contributions, indirect.rays.size());
}

// Cornell box: the splat image against the path tracer at high spp. Relative MSE (per
// channel, (a − b)² / (b² + 0.01)) below 0.05: density estimation blurs and is noisy at
// 100k photons, but a wrong normalisation (a factor 2), missing visibility or a missing class
// each push it far above that (measured: ≥ 0.2).
TEST(SplatRenderer, CornellBoxCloseToPathTracer) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    Scene scene = loadScene(std::string(data) + "/cornell_box.gltf", silentReporter());
    RenderConfig cfg = splatConfig(64);
    cfg.height = 0;
    RenderResult splat = render(scene, cfg, silentReporter());
    cfg.method = Method::Path;
    cfg.spp = 1024;
    RenderResult path = render(scene, cfg, silentReporter());
    double e = relativeMse(splat.film.beautyImage(), path.film.beautyImage());
    RecordProperty("relative_mse", std::to_string(e));
    EXPECT_LT(e, 0.05);
}

// The indirect kernels' scale, measured by the first pass (splat/kernel_scale.h): under a point
// light, whose indirect light has contact shadows, it shrinks the kernels and the indirect
// layer comes closer to the path tracer's (measured at 96 px, 2 passes: 0.66 of the error at
// scale 1, chosen 0.59); in the Cornell box, whose indirect light is smooth, it leaves them.
TEST(KernelScale, ChosenByTheSceneAgainstThePathTracer) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    auto defaults = [] {  // the default render, 96 px, 2 passes
        RenderConfig cfg;
        cfg.output = "unused.exr";
        cfg.width = cfg.height = 96;
        cfg.passes = 2;
        return cfg;
    };
    Scene point = loadScene(std::string(data) + "/point_shadows.gltf", silentReporter());
    RenderConfig cfg = defaults();
    const RenderResult chosen = render(point, cfg, silentReporter());
    cfg.kernelScale = 1.f;
    const RenderResult whole = render(point, cfg, silentReporter());
    cfg.method = Method::Path;
    cfg.passes = 1;
    cfg.spp = 2048;
    const RenderResult path = render(point, cfg, silentReporter());
    const float m = float(chosen.stats.count("kernel_scale"));
    EXPECT_LT(m, 0.8f);
    EXPECT_GE(m, kMinKernelScale);
    const double e = relativeMse(chosen.film.layers[kIndirect], path.film.layers[kIndirect]);
    const double e1 = relativeMse(whole.film.layers[kIndirect], path.film.layers[kIndirect]);
    RecordProperty("indirect_error_ratio", std::to_string(e / e1));
    EXPECT_LT(e, 0.8 * e1) << "scale " << m;

    Scene cornell = loadScene(std::string(data) + "/cornell_box.gltf", silentReporter());
    EXPECT_EQ(render(cornell, defaults(), silentReporter()).stats.count("kernel_scale"), 1.0);
}

TEST(SplatRenderer, ThreadCountDoesNotChangePixels) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    Scene scene = loadScene(std::string(data) + "/glossy_box.glb", silentReporter());
    RenderConfig cfg = splatConfig(40);
    cfg.photons = 20000;
    RenderResult a = expectSamePixelsWhateverTheThreadCount(scene, cfg);
    double caustic = 0;
    for (const Vec3& v : a.film.layers[kCaustic]) caustic += v.x;
    EXPECT_GT(caustic, 0.0) << "the glass sphere makes caustics";
}

// --photon replays one photon ray: the same ray as in the full render (the same path, radius,
// coverage and receivers), so the replays of every ray of every pass add up to the passes'
// photon light. On the glossy box (indirect and caustic rays, glass), `photons` a pass.
void expectReplaysAddUp(int passes, int photons) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    Scene scene = loadScene(std::string(data) + "/glossy_box.glb", silentReporter());
    RenderConfig cfg = splatConfig(24);
    cfg.height = 0;
    cfg.photons = photons;
    cfg.passes = passes;
    const RenderResult full = render(scene, cfg, silentReporter());
    EXPECT_EQ(full.stats.count("kernel_probe_noise") > 0.0, passes > 1) << "the scale is measured with passes to follow";
    std::vector<Vec3> sum(full.film.layers[kIndirect].size(), Vec3(0.f));
    std::vector<Vec3> caustic = sum;
    for (int pass = 0; pass < passes; ++pass) {
        cfg.replayPass = pass;  // of the render of `passes` passes
        for (int i = 0; i < photons; ++i) {
            cfg.replayIndex = i;
            const RenderResult one = render(scene, cfg, silentReporter());
            for (size_t p = 0; p < sum.size(); ++p) {
                sum[p] += one.film.layers[kIndirect][p];
                caustic[p] += one.film.layers[kCaustic][p];
                ASSERT_EQ(one.film.layers[kEmission][p], Vec3(0.f)) << "the eye pass's own light is left out";
            }
        }
    }
    double light = 0.0;
    const float n = float(passes);
    for (size_t p = 0; p < sum.size(); ++p) {
        for (int c = 0; c < 3; ++c) {
            const float indirect = n * full.film.layers[kIndirect][p][c], caustics = n * full.film.layers[kCaustic][p][c];
            EXPECT_NEAR(sum[p][c], indirect, 1e-5f * (1.f + indirect));
            EXPECT_NEAR(caustic[p][c], caustics, 1e-5f * (1.f + caustics));
        }
        light += sum[p].x + caustic[p].x;
    }
    EXPECT_GT(light, 0.0) << "not vacuous";
    cfg.replayIndex = photons;
    EXPECT_THROW(render(scene, cfg, silentReporter()), Error) << "past the pass's rays";
}

TEST(SplatRenderer, ReplayedPhotonsAddUpToTheirPass) { expectReplaysAddUp(1, 40); }

// Over two passes the first measures the kernel scale (splat/kernel_scale.h) and splats its
// indirect photons in parts, each with its own scale and coverage: the replays follow it.
TEST(SplatRenderer, ReplayedPhotonsAddUpUnderTheKernelScaleProbe) { expectReplaysAddUp(2, 24); }

// A time limit no pass can keep (here past as soon as the passes begin): the first pass stops
// after its first portion of photons (whole paths), counts the share of each class's paths it
// splatted, and its photon layers are that share's light over the share. Its eye pass has
// the least eye samples and direct film (eyePassWithin): the direct layer is that of a pass
// of 2 film samples to the bit, and the indirect layer's mean is a whole pass's (at kernel scale
// 1) within the noise of the photons splatted. `probe`: the pass probes the kernel
// scale (docs/design.md §7), whose share of the indirect photons (half of them, at two scales)
// stops at the deadline as the splat does.
void expectCutShortPass(bool probe, double tolerance) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    Scene scene = loadScene(std::string(data) + "/interior.gltf", silentReporter());
    RenderConfig cfg = splatConfig(48);
    cfg.height = 0;
    cfg.photons = 200000;
    cfg.kernelScale = 1.f;
    const RenderResult whole = render(scene, cfg, silentReporter());
    const int directSpp = cfg.directSpp;
    cfg.directSpp = 2;
    const RenderResult film2 = render(scene, cfg, silentReporter());
    cfg.directSpp = directSpp;
    cfg.kernelScale = probe ? 0.f : 1.f;
    cfg.passes = 0;
    cfg.timeLimit = 1e-6;
    ASSERT_EQ(cfg.probesKernelScale(), probe);
    const RenderResult cut = render(scene, cfg, silentReporter());
    EXPECT_EQ(cut.stats.count("passes"), 1.0);
    if (probe) {  // cut short: no scale chosen, the probed paths' light kept at 1
        EXPECT_EQ(cut.stats.count("kernel_probe_widened"), 0.0);
        EXPECT_EQ(cut.stats.count("kernel_probe_cut"), 1.0);
        EXPECT_EQ(cut.stats.count("kernel_scale"), 1.0);
    }
    const double share = cut.stats.count("photon_passes");
    ::testing::Test::RecordProperty("indirect_share", std::to_string(share));
    EXPECT_GT(share, 0.0);
    EXPECT_LT(share, 2.0 / PassTargets::kPortions) << "one portion of sixteen, to whole paths";
    // The eye pass sized to the time left: its direct film at the least, 2 samples a pixel
    // (of a whole pass's 16), the film of a pass of 2 to the bit, and 1 eye sample (of 4).
    EXPECT_EQ(cut.stats.count("first_pass_direct_spp"), 2.0);
    EXPECT_EQ(cut.stats.count("first_pass_spp"), 1.0);
    EXPECT_EQ(cut.film.layers[kDirect], film2.film.layers[kDirect]);
    EXPECT_NE(cut.film.layers[kDirect], whole.film.layers[kDirect]);
    const double ratio = layerMean(cut.film, kIndirect) / layerMean(whole.film, kIndirect);
    ::testing::Test::RecordProperty("indirect_mean_ratio", std::to_string(ratio));
    EXPECT_NEAR(ratio, 1.0, tolerance);
}

// A sixteenth of the photons, about 12 k: measured 0.063 of the pass and a mean of 1.0003.
TEST(TimeLimit, APassCutShortKeepsAnUnbiasedShareOfItsPhotons) { expectCutShortPass(false, 0.04); }

// The probe's first portion: measured 0.031 of the pass's indirect photons (the whole share
// gave 0.53) and a mean of 1.005.
TEST(TimeLimit, TheKernelScaleProbeStopsAtTheDeadlineToo) { expectCutShortPass(true, 0.05); }

// Passes of the direct film alone (--film-passes; what a time limit's leftover time goes to): the
// film's layers are those of as many whole passes, the photons' those of the whole passes alone,
// both to the bit, since film pass p takes the direct film samples whole pass p would.
TEST(FilmPasses, AddTheDirectFilmOfWholePassesAndNoPhotons) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    const Scene scene = loadScene(std::string(data) + "/cornell_box.gltf", silentReporter());
    RenderConfig cfg = splatConfig(24);
    cfg.photons = 4000;
    cfg.kernelScale = 1.f;
    cfg.passes = 2;
    const RenderResult two = render(scene, cfg, silentReporter());
    cfg.filmPasses = 2;
    const RenderResult film = render(scene, cfg, silentReporter());
    cfg.filmPasses = 0;
    cfg.passes = 4;
    const RenderResult four = render(scene, cfg, silentReporter());
    EXPECT_EQ(film.stats.count("film_passes"), 2.0);
    EXPECT_EQ(film.stats.count("passes"), 2.0);
    for (int l : {kDirect, kEmission}) EXPECT_EQ(film.film.layers[l], four.film.layers[l]) << layerName(l);
    EXPECT_EQ(film.film.albedo, four.film.albedo);
    EXPECT_EQ(film.film.normal, four.film.normal);
    for (int l : {kIndirect, kCaustic}) EXPECT_EQ(film.film.layers[l], two.film.layers[l]) << layerName(l);
    EXPECT_NE(film.film.layers[kDirect], two.film.layers[kDirect]);
}

// Photon rounds (--photon-rounds, docs/design.md §9): R rounds of M photons on one eye pass are
// a pass of R·M photons, whose kernels they take. Over two seeds, the indirect kernels of one
// size whatever the photons: the eye pass's layers are one round's to the bit; the indirect
// light has the mean of a pass of R·M photons and about its noise (the seeds' squared
// difference), less than one round's (measured 0.80: the photons' part halves, the eye samples'
// stays); the same to the bit whatever the thread count. A pass of R rounds spaces its receivers
// 1/√R as far apart (docs/design.md §8): here each render's receivers are given the spacing of
// one round, and a pass of two rounds at the default spacing has more receivers (twice as many
// on a large surface; measured 1.51 here, where the 16-pixel tiles and the small surfaces of a
// 48-pixel image keep receivers of their own).
TEST(PhotonRounds, AreAPassOfTheirPhotonsTogether) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    const Scene scene = loadScene(std::string(data) + "/interior.gltf", silentReporter());
    RenderConfig cfg = splatConfig(48);
    cfg.height = 0;
    cfg.kernelScale = 1.f;
    cfg.minRadius[kPhotonIndirect] = cfg.maxRadius[kPhotonIndirect] = 8.f;
    const float spacing = cfg.receiverSpacing;
    auto seeds = [&](int64_t photons, int rounds) {
        cfg.photons = photons;
        cfg.photonRounds = rounds;
        cfg.receiverSpacing = spacing * std::sqrt(float(rounds));
        std::vector<RenderResult> r;
        for (uint64_t seed : {1, 2}) {
            cfg.seed = seed;
            r.push_back(render(scene, cfg, silentReporter()));
        }
        return r;
    };
    auto noise = [](const std::vector<RenderResult>& r) {
        double e = 0.0;
        for (size_t p = 0; p < r[0].film.pixelCount(); ++p) {
            const Vec3 d = r[0].film.layers[kIndirect][p] - r[1].film.layers[kIndirect][p];
            e += glm::dot(d, d);
        }
        return e;
    };
    auto mean = [](const std::vector<RenderResult>& r) { return layerMean(r[0].film, kIndirect) + layerMean(r[1].film, kIndirect); };
    const std::vector<RenderResult> one = seeds(20000, 1), two = seeds(20000, 2), together = seeds(40000, 1);
    EXPECT_EQ(two[0].stats.count("photons_stored"), 2.0 * one[0].stats.count("photons_stored"));
    EXPECT_EQ(two[0].stats.count("photon_passes"), 2.0) << "each round counts";
    for (int l : {kDirect, kEmission}) EXPECT_EQ(two[0].film.layers[l], one[0].film.layers[l]) << layerName(l);
    const double meanRatio = mean(two) / mean(together), ofOne = noise(two) / noise(one), ofTogether = noise(two) / noise(together);
    RecordProperty("indirect_mean_ratio", std::to_string(meanRatio));
    RecordProperty("noise_of_one_round", std::to_string(ofOne));
    RecordProperty("noise_of_one_pass", std::to_string(ofTogether));
    EXPECT_NEAR(meanRatio, 1.0, 0.03);
    EXPECT_GT(ofOne, 0.3);
    EXPECT_LT(ofOne, 0.85) << "a round's photons the same as the first's would give 1";
    EXPECT_GT(ofTogether, 0.7);
    EXPECT_LT(ofTogether, 1.4);
    const double receivers = one[0].stats.count("receivers");
    EXPECT_NEAR(two[0].stats.count("receivers") / receivers, 1.0, 0.02) << "one round's spacing";
    cfg.photonRounds = 2;
    cfg.photons = 20000;
    cfg.receiverSpacing = spacing;
    cfg.seed = 1;
    const double closer = render(scene, cfg, silentReporter()).stats.count("receivers") / receivers;
    RecordProperty("receivers_of_two_rounds", std::to_string(closer));
    EXPECT_GT(closer, 1.3) << "two rounds' receivers 1/√2 as far apart";
    EXPECT_LT(closer, 2.4);
    expectSamePixelsWhateverTheThreadCount(scene, cfg);
}

// A walkthrough's photon store (docs/design.md §12): photons traced for one camera and splatted
// into another's frame give that frame bit for bit the image its own render gives, with the
// coverage measured for every photon where the splat measures it only for those it needs; the
// second frame traces no photons.
TEST(PhotonStore, FramesShareThePhotonsAndKeepTheirImages) {
    const char* data = std::getenv("RAYSPLAT_DATA");
    if (!data) GTEST_SKIP() << "RAYSPLAT_DATA not set";
    Scene first = loadScene(std::string(data) + "/interior.gltf", silentReporter());
    RenderConfig cfg = splatConfig(40);
    cfg.photons = 20000;
    cfg.passes = 2;
    cfg.kernelScale = 1.f;  // a store's photons are not probed: the same scale without one
    Scene second = first;
    Camera& cam = second.cameras.at(0);
    cam.position += 0.3f * cam.right + 0.1f * cam.forward;
    auto same = [](const RenderResult& a, const RenderResult& b) {
        for (int l = 0; l < kLayerCount; ++l)
            if (a.film.layers[l] != b.film.layers[l]) return false;
        return true;
    };
    PhotonStore store;
    const RenderResult a = render(first, cfg, silentReporter(), singleProcess(), &store);
    EXPECT_EQ(store.traced, 2);
    EXPECT_TRUE(same(a, render(first, cfg, silentReporter()))) << "coverage measured for all photons or as needed";
    const RenderResult b = render(second, cfg, silentReporter(), singleProcess(), &store);
    EXPECT_EQ(store.traced, 2) << "the second frame reuses both passes";
    EXPECT_EQ(b.stats.count("photon_passes_traced"), 0.0) << "by this render";
    EXPECT_EQ(a.stats.count("photon_passes_traced"), 2.0);
    EXPECT_GT(b.stats.count("splat_contributions"), 0.0);
    EXPECT_TRUE(same(b, render(second, cfg, silentReporter()))) << "frame b alone";
    PhotonStore fresh;
    EXPECT_TRUE(same(b, render(second, cfg, silentReporter(), singleProcess(), &fresh))) << "frame b first";
    EXPECT_FALSE(same(a, b)) << "the camera moved";
}
