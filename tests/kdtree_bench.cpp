// Occlusion tree benchmark (`meson test --benchmark`): build time and memory at 192³ for a
// synthetic glossy-box-like grid (a room of five walls, a sphere and an octahedron, surfaces
// one voxel thick with counts from the surface orientation) with 1 000 000 eye samples on
// the surfaces (500×500×4), and cylinder traversal throughput for radii 1, 2, 4, 8 voxels
// with one thread and with all threads. Medians of 3 runs. Paper (Table 1, glossy box,
// 192³): 5 MB tree, 26 MB eye samples.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "occlusion/kdtree.h"
#include "occlusion/kdtree_traverse.h"
#include "core/stats.h"

using namespace rs;

namespace {

constexpr int kRes = 192;

struct Surfaces {
    OcclusionGrid grid;
    std::vector<Vec3> points, normals;  // eye sample candidates, voxel space
};

// Counts of a surface with unit normal n covering a voxel: the projection along each axis
// covers about |n_a| of the face (capped at 16).
void addSurfaceVoxel(OcclusionGrid& grid, IVec3 v, Vec3 n) {
    if (!grid.geometry.contains(v.x, v.y, v.z)) return;
    uint8_t* c = grid.voxel(grid.geometry.index(v.x, v.y, v.z));
    for (int a = 0; a < 3; ++a) {
        int count = int(std::lround(16.f * std::abs(n[a])));
        if (count == 0) continue;
        uint8_t& side = c[n[a] > 0.f ? 2 * a : 2 * a + 1];
        side = uint8_t(std::min(16, side + count));
    }
}

Surfaces glossyBox() {
    GridGeometry g;
    g.dims = IVec3(kRes);
    Surfaces s{OcclusionGrid(g), {}, {}};
    // The room: floor, ceiling, back, left and right walls, normals inwards (+Y up).
    const int lo = 1, hi = kRes - 2;
    for (int i = lo; i <= hi; ++i)
        for (int j = lo; j <= hi; ++j) {
            addSurfaceVoxel(s.grid, {i, lo, j}, {0, 1, 0});
            addSurfaceVoxel(s.grid, {i, hi, j}, {0, -1, 0});
            addSurfaceVoxel(s.grid, {i, j, lo}, {0, 0, 1});
            addSurfaceVoxel(s.grid, {lo, i, j}, {1, 0, 0});
            addSurfaceVoxel(s.grid, {hi, i, j}, {-1, 0, 0});
        }
    // A sphere and an octahedron ("icosahedron-ish") standing on the floor.
    const Vec3 sc(62.f, 42.f, 80.f), oc(132.f, 44.f, 112.f);
    const float sr = 40.f, orad = 42.f;
    for (int z = 0; z < kRes; ++z)
        for (int y = 0; y < kRes; ++y)
            for (int x = 0; x < kRes; ++x) {
                Vec3 p = Vec3(x, y, z) + Vec3(0.5f);
                Vec3 d = p - sc;
                float dist = glm::length(d) - sr;
                if (std::abs(dist) < 0.87f) addSurfaceVoxel(s.grid, {x, y, z}, d / glm::length(d));
                Vec3 e = p - oc;
                float l1 = std::abs(e.x) + std::abs(e.y) + std::abs(e.z) - orad;
                if (std::abs(l1) < 0.87f * 1.732f)
                    addSurfaceVoxel(s.grid, {x, y, z}, glm::normalize(Vec3(e.x >= 0 ? 1 : -1, e.y >= 0 ? 1 : -1, e.z >= 0 ? 1 : -1)));
            }
    // Eye sample candidates: points on the surfaces, by area.
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    const int n = 500 * 500 * 4;
    s.points.reserve(n);
    s.normals.reserve(n);
    for (int i = 0; i < n; ++i) {
        float pick = u01(rng) * 7.f;
        float a = lo + u01(rng) * (hi + 1 - lo), b = lo + u01(rng) * (hi + 1 - lo);
        Vec3 p, nrm;
        if (pick < 1) p = {a, lo + 0.5f, b}, nrm = {0, 1, 0};
        else if (pick < 2) p = {a, hi + 0.5f, b}, nrm = {0, -1, 0};
        else if (pick < 3) p = {a, b, lo + 0.5f}, nrm = {0, 0, 1};
        else if (pick < 4) p = {lo + 0.5f, a, b}, nrm = {1, 0, 0};
        else if (pick < 5) p = {hi + 0.5f, a, b}, nrm = {-1, 0, 0};
        else {
            std::normal_distribution<float> gauss;
            Vec3 d = glm::normalize(Vec3(gauss(rng), gauss(rng), gauss(rng)));
            if (pick < 6) {
                p = sc + d * sr, nrm = d;
            } else {
                d /= std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
                p = oc + d * orad;
                nrm = glm::normalize(Vec3(d.x >= 0 ? 1 : -1, d.y >= 0 ? 1 : -1, d.z >= 0 ? 1 : -1));
            }
        }
        s.points.push_back(p);
        s.normals.push_back(nrm);
    }
    return s;
}

EyeSamples makeSamples(const Surfaces& s) {
    EyeSamples e;
    e.reserve(s.points.size());
    for (size_t i = 0; i < s.points.size(); ++i) {
        e.add(s.grid.geometry.worldFromVoxel(s.points[i]), s.normals[i], s.normals[i], false, uint32_t(i / 4), Vec3(0.25f));
    }
    return e;
}

double median3(double a, double b, double c) { return std::max(std::min(a, b), std::min(std::max(a, b), c)); }

}  // namespace

int main(int argc, char** argv) {
    // Optional arguments: the radii to time (default 1 2 4 8), e.g. `kdtree_bench 8` for a profile.
    std::vector<float> radii;
    for (int i = 1; i < argc; ++i) radii.push_back(std::strtof(argv[i], nullptr));
    if (radii.empty()) radii = {1.f, 2.f, 4.f, 8.f};
    ThreadPool pool(0);
    std::printf("kdtree benchmark: %d³ synthetic glossy box, %d threads\n", kRes, pool.size());
    Timer setup;
    Surfaces surfaces = glossyBox();
    std::printf("  grid: %zu occupied voxels (made in %.2f s)\n", surfaces.grid.occupiedCount(), setup.seconds());

    // Build: medians of 3.
    double total[3], sat[3], build[3], sort[3];
    OcclusionTree tree;
    EyeSamples samples;
    OcclusionTreeStats st;
    for (int run = 0; run < 3; ++run) {
        samples = makeSamples(surfaces);
        tree = buildOcclusionTree(surfaces.grid, samples, pool, &st);
        total[run] = st.totalSeconds, sat[run] = st.satSeconds, build[run] = st.buildSeconds, sort[run] = st.sortSeconds;
    }
    std::printf("\n  build (median of 3): total %.3f s = SAT %.3f s + recursion %.3f s + sample sort/permute %.3f s\n",
                median3(total[0], total[1], total[2]), median3(sat[0], sat[1], sat[2]),
                median3(build[0], build[1], build[2]), median3(sort[0], sort[1], sort[2]));
    std::printf("  nodes %zu: empty %zu, split %zu, occlusion %zu (%zu voxels collapsed), brick %zu (%zu voxels); depth %d\n",
                st.nodes, st.empty, st.split, st.occlusion, st.collapsedVoxels, st.bricks, st.brickVoxels, st.depth);
    const double mb = 1.0 / (1024.0 * 1024.0);
    std::printf("  memory: tree %.2f MB (paper 5), eye samples %.2f MB for %zu (paper 26), SAT (temporary) %.1f MB\n",
                double(st.bytes) * mb, double(samples.bytes()) * mb, samples.size(),
                double(kRes + 1) * (kRes + 1) * (kRes + 1) * 4 * mb);
    std::printf("  samples outside the grid: %zu\n", st.samplesOutside);

    // Cylinders from random surface points, random directions into the normal's hemisphere.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::normal_distribution<float> gauss;
    const size_t count = 1 << 16;
    std::vector<Cylinder> cylinders(count);
    for (Cylinder& c : cylinders) {
        size_t i = size_t(u01(rng) * float(tree.sampleCount)) % tree.sampleCount;
        Vec3 n = decodeUnit(samples.normal[i]);
        Vec3 d = glm::normalize(Vec3(gauss(rng), gauss(rng), gauss(rng)));
        if (glm::dot(d, n) < 0.f) d = -d;
        c.origin = tree.geometry.voxelFromWorld(samples.position[i]);
        c.dir = d;
        c.originNormal = n;
        c.length = u01(rng) * kRes;
    }

    std::printf("\n  traversal, up to %zu cylinders a run (~0.4 s), length U(0, %d), medians of 3\n", count, kRes);
    std::printf("  %6s | %14s | %14s | %8s | %9s %9s %9s %9s %9s %9s %9s\n", "radius", "1 thread (c/s)", "all thr. (c/s)",
                "speedup", "nodes/c", "occl./c", "tested/c", "samples/c", "swept/c", "boxed/c", "visited/c");
    double checksum = 0;
    for (float radius : radii) {
        for (Cylinder& c : cylinders) c.radius = radius;
        double rate[2][3];
        TraversalStats ts;
        // Calibrate: each run takes about 0.4 s (the whole benchmark stays under a minute).
        size_t calibrate = 512;
        {
            TraversalScratch scratch;
            Timer t;
            for (size_t i = 0; i < calibrate; ++i)
                traverseCylinder(tree, samples, cylinders[i], scratch, [&](uint32_t, float v) { checksum += v; });
            calibrate = size_t(double(calibrate) / t.seconds() * 0.4);
        }
        for (int mode = 0; mode < 2; ++mode) {
            ThreadPool one(1);
            ThreadPool& p = mode == 0 ? one : pool;
            const size_t n = std::clamp(calibrate * size_t(mode == 0 ? 1 : p.size()), size_t(1024), count);
            for (int run = 0; run < 3; ++run) {
                std::vector<TraversalScratch> scratch(size_t(p.size()));
                std::vector<TraversalStats> stats(size_t(p.size()));
                std::vector<double> sums(size_t(p.size()), 0.0);
                Timer t;
                p.parallelFor(int64_t(n), 256, [&](int64_t b, int64_t e, int thread) {
                    double sum = 0;
                    // The visitor takes the lists the splat takes (their V summed for the checksum).
                    auto visit = Overloaded{[&](uint32_t, float v) { sum += v; },
                                            [&](const uint32_t*, size_t count) { sum += double(count); },
                                            [&](const uint32_t*, const float* v, size_t count) {
                                                float s = 0.f;
                                                for (size_t k = 0; k < count; ++k) s += v[k];
                                                sum += s;
                                            }};
                    for (int64_t i = b; i < e; ++i)
                        traverseCylinder(tree, samples, cylinders[size_t(i)], scratch[size_t(thread)], visit, &stats[size_t(thread)]);
                    sums[size_t(thread)] += sum;
                });
                rate[mode][run] = double(n) / t.seconds();
                for (double s : sums) checksum += s;
                if (mode == 1 && run == 0)
                    for (const TraversalStats& x : stats) ts.add(x);
            }
        }
        double r1 = median3(rate[0][0], rate[0][1], rate[0][2]), rn = median3(rate[1][0], rate[1][1], rate[1][2]);
        double per = 1.0 / double(ts.cylinders);
        std::printf("  %6.0f | %14.0f | %14.0f | %7.2fx | %9.1f %9.1f %9.1f %9.1f %9.1f %9.1f %9.1f\n", double(radius), r1, rn,
                    rn / r1, double(ts.nodes) * per, double(ts.occluders) * per, double(ts.samplesTested) * per,
                    double(ts.samplesReached) * per, double(ts.samplesSwept) * per, double(ts.samplesBoxed) * per,
                    double(ts.samplesVisited) * per);
    }
    std::printf("  (checksum %.3g)\n", checksum);
    return 0;
}
