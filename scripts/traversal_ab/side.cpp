// One side of the in-process comparison (run.sh): a revision's kd-tree benchmark scene, tree and
// cylinders, and its traversal timed on demand. Compiled once per revision with -Drs=rs_a or
// -Drs=rs_b, so that both revisions' code lives in one program under different namespaces.
// RS_AB_FLAT: a revision from before lib/ had folders, whose visitor takes (index, V) only.
#define main static benchmarkMainUnused  // "int static …": the benchmark's own main, unused
#include "kdtree_bench.cpp"
#undef main

#include <memory>

namespace rs {

struct AbSide {
    Surfaces surfaces;
    OcclusionTree tree;
    EyeSamples samples;
    std::vector<Cylinder> cylinders;
    std::unique_ptr<ThreadPool> all, one;
};

// The benchmark's scene, tree and cylinders (the same seeds as kdtree_bench).
AbSide* abSetUp() {
    auto* s = new AbSide{glossyBox(), {}, {}, {}, std::make_unique<ThreadPool>(0), std::make_unique<ThreadPool>(1)};
    s->samples = makeSamples(s->surfaces);
    s->tree = buildOcclusionTree(s->surfaces.grid, s->samples, *s->all, nullptr);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::normal_distribution<float> gauss;
    s->cylinders.resize(size_t(1) << 16);
    for (Cylinder& c : s->cylinders) {
        const size_t i = size_t(u01(rng) * float(s->tree.sampleCount)) % s->tree.sampleCount;
        const Vec3 n = decodeUnit(s->samples.normal[i]);
        Vec3 d = glm::normalize(Vec3(gauss(rng), gauss(rng), gauss(rng)));
        if (glm::dot(d, n) < 0.f) d = -d;
        c.origin = s->tree.geometry.voxelFromWorld(s->samples.position[i]);
        c.dir = d;
        c.originNormal = n;
        c.length = u01(rng) * kRes;
    }
    return s;
}

// Cylinders a second over `count` cylinders of radius `radius` (voxels), on one thread or on
// all; the visited samples' V summed into `checksum`.
double abRate(AbSide* s, float radius, bool allThreads, size_t count, double& checksum) {
    for (Cylinder& c : s->cylinders) c.radius = radius;
    ThreadPool& pool = allThreads ? *s->all : *s->one;
    std::vector<TraversalScratch> scratch(size_t(pool.size()));
    std::vector<double> sums(size_t(pool.size()), 0.0);
    Timer timer;
    pool.parallelFor(int64_t(count), 256, [&](int64_t b, int64_t e, int thread) {
        double sum = 0;
#if RS_AB_FLAT
        auto visit = [&](uint32_t, float v) { sum += v; };
#else
        auto visit = Overloaded{[&](uint32_t, float v) { sum += v; }, [&](const uint32_t*, size_t n) { sum += double(n); },
                                [&](const uint32_t*, const float* v, size_t n) {
                                    float t = 0.f;
                                    for (size_t k = 0; k < n; ++k) t += v[k];
                                    sum += t;
                                }};
#endif
        for (int64_t i = b; i < e; ++i)
            traverseCylinder(s->tree, s->samples, s->cylinders[size_t(i) % s->cylinders.size()], scratch[size_t(thread)], visit);
        sums[size_t(thread)] += sum;
    });
    const double seconds = timer.seconds();
    for (double v : sums) checksum += v;
    return double(count) / seconds;
}

}  // namespace rs
