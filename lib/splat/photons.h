// Photon tracing (docs/design.md §7, paper §3): paths from the lights with a scrambled Halton
// sequence indexed by the path number; every segment x(i−1) → x(i) that ends on a
// non-specular surface is stored as a photon ray of class direct, caustic or indirect, with
// per-class quotas, flux normalised by the paths emitted until the class's quota filled, and
// a splat radius from the path pdf. World space, metres; flux in W.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "core/math.h"
#include "core/sampling.h"
#include "splat/kernel_edge.h"

namespace rs {

class RayAccel;
class LightSampler;
class ThreadPool;
class Reporter;
struct Scene;

enum PhotonClass : uint8_t { kPhotonDirect = 0, kPhotonIndirect = 1, kPhotonCaustic = 2, kPhotonClassCount = 3 };
const char* photonClassName(int c);

struct PhotonRay {
    Vec3 origin;        // x(i−1)
    float length;       // distance to x(i), the surface it ends on
    Vec3 dir;           // unit
    float radius;       // splat radius h, metres
    Vec3 flux;          // W, already divided by the class's path count
    uint32_t originNormal;  // encodeUnit of the tangent plane's normal at x(i−1) (side of dir); 0: none
    float density;      // p⊥ of the photon at x(i) per path (1/m²), for the radius
    float reach;        // how far past x(i) the kernel reaches, in radii: tan θ at x(i), clamped to [1, 16]
                        // (with PhotonSettings::reachToBounds, at least to where the ray leaves the scene)
    uint8_t cls;        // PhotonClass
    uint8_t pad[3] = {0, 0, 0};  // no indeterminate bytes: photon arrays compare with memcmp
    // The index of its path among the pass's (from PhotonSettings::firstPath): the photons of
    // paths [0, P) are an unbiased share P / N_c of their class's light (a pass cut short by a
    // time limit splats such a share).
    uint32_t path = 0;

    // A segment meeting a flat receiver at angle θ from its normal puts the parallel rays of
    // its kernel disc down up to h·tan θ past x(i): the cylinder must reach that far.
    static float reachOf(float cosTheta);

    // Where along the ray, from x(i−1), surfaces take the kernel's light: up to one reach past
    // x(i), and, `windowed`, only within kReceiverWindow radii of x(i) (docs/design.md §8). A
    // surface the photon passed long before its end, or one far behind it, is not where its
    // neighbours in the kernel went: through a blind's slats, photons bound for the ceiling put
    // their light on the slats' undersides. Coverage and splat keep the same window.
    static constexpr float kReceiverWindow = 8.f;
    float kernelBegin(bool windowed) const { return windowed ? std::max(0.f, length - kReceiverWindow * radius) : 0.f; }
    float kernelEnd(bool windowed) const {
        return length + radius * (windowed ? std::min(reach, kReceiverWindow) : reach);
    }
};

// One number per photon class: direct, indirect, caustic.
using ClassTriple = std::array<float, kPhotonClassCount>;

// The defaults here are the renderer's (RenderConfig takes them from a PhotonSettings{}).
struct PhotonSettings {
    int64_t photons = 100000;                 // M, total stored photon rays
    ClassTriple split = {0.2f, 0.5f, 0.3f};   // the paper's
    // Photons wanted under a kernel, and the radius clamps (voxels), measured against
    // path-traced references (docs/design.md §7): direct kernels hold 24 photons, since their
    // few photons spread thin; indirect kernels stop at 10 voxels, past which they cost most of
    // the splat for no accuracy; the 6-voxel indirect floor halves the error in closed rooms.
    ClassTriple k = {24.f, 40.f, 16.f};
    // Indirect photons leaving a glossy lobe get a sharp pdf, hence tiny radii and sparkles: a
    // 6-voxel floor halved the error on both boxes (glossy 0.084 → 0.042, Cornell 0.030 → 0.018).
    ClassTriple minRadius = {1.f, 6.f, 1.f};
    ClassTriple maxRadius = {16.f, 10.f, 16.f};
    float voxelSize = 0.01f;                 // metres, to express the clamps
    int maxDepth = kDefaultMaxDepth;         // segments a path
    uint64_t seed = 0;
    uint64_t firstPath = 0;                  // sequence offset (progressive passes)
    static constexpr int kPathsPerPassBits = 40;  // pass p traces paths from p · 2^40: ranges never overlap
    static constexpr int kPathsPerRoundBits = 32;  // and its round r (after the first) from there + r · 2^32
    float radiusScale = 1.f;                 // this pass's kernel shrinkage, applied after the clamps
    int rounds = 1;                          // the pass's photon rounds: kernels hold k photons of them all
    ClassTriple classScale = {1.f, 1.f, 1.f}; // and per class (the indirect kernels' scale, kernel_scale.h)
    // The kernel reaches on past x(i) to the scene's bounds (the splat and the coverage stop
    // kReceiverWindow radii past it): with visibility by rays alone (--visibility rays) a
    // sample beyond x(i) receives only where it sees x(i−1), past the edge of what the photon
    // hit, so a kernel that half-misses a convex edge or a thin part loses nothing there. (Cut
    // at reachOf, the staircase interior's indirect light lost 4 % more.)
    bool reachToBounds = false;
    int64_t maxPaths = 0;                    // 0: 50 × photons (at most 2^32 − 1: PhotonRay::path)
};

struct Stats;

struct PhotonMap {
    std::vector<PhotonRay> rays;               // in path order
    // Kept in a walkthrough's store: each ray's kernel edges, its coverage already measured and
    // its flux divided (normalizeKernelCoverage). Empty: the splat measures them.
    std::vector<KernelEdge> edges;
    int64_t pathsFor[kPhotonClassCount] = {};  // N_c: paths emitted until the quota filled
    int64_t count[kPhotonClassCount] = {};
    int64_t pathsTraced = 0;
    size_t bytes() const { return rays.size() * sizeof(PhotonRay) + edges.size() * sizeof(KernelEdge); }
    void report(Stats& stats) const;  // photons_<class> and photon_paths counts
};

// The photons of class `cls` alone, their kernels scaled by `factor` < 1, as tracePhotons would
// give them with classScale[cls] × factor (before their coverage is measured).
PhotonMap scaledKernels(const Scene& scene, const PhotonMap& photons, int cls, float factor, const PhotonSettings& settings);

PhotonMap tracePhotons(const Scene& scene, const RayAccel& accel, const LightSampler& lights,
                       const PhotonSettings& settings, ThreadPool& pool, Reporter& reporter);

}  // namespace rs
