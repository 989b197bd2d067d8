// Kernel coverage (docs/design.md §8): the share of a photon ray's kernel that lands on a
// surface which may receive it. A kernel is a disc of parallel rays around the photon's own;
// near a concave corner part of the disc starts behind the surface the photon leaves, past a
// convex edge or a thin part it lands on nothing within the cylinder, and on fine geometry on
// samples the receiver rules refuse. That part's light is lost, and more of it the larger the
// kernel. Probes along the disc's rays, distributed as the kernel, measure the share that
// arrives; the photon's flux is divided by it, so each photon delivers its flux.
// World space; the probes are Embree rays.
#pragma once

#include <cstdint>

namespace rs {

class RayAccel;
class ThreadPool;
class Reporter;
struct PhotonMap;
struct Stats;

struct CoverageSettings {
    static constexpr int kMaxProbes = 16;  // one Embree packet
    // Rays a photon, distributed as the biweight kernel. On the staircase interior at 180 px,
    // 2 passes, the indirect layer's mean over the path tracer's was 1.028 with 8, 1.025 with
    // 16 and 1.023 with 32 (0.917 with none); 16 fill the packet.
    int probes = kMaxProbes;
    uint64_t seed = 0;       // with the pass: the probes' rotation, a function of (seed, pass, photon)
    uint64_t pass = 0;
};

struct CoverageStats {
    uint64_t photons = 0, partial = 0, uncovered = 0;  // photons probed; with coverage below 1; with none
    double coverageSum = 0.0;                          // sum of the photons' coverage
    void add(const CoverageStats& o);
    void report(Stats& stats) const;
};

// Measures each photon ray's kernel coverage c and divides its flux by c (photons whose probes
// all miss keep their flux: nothing measured to divide by). The result does not depend on the
// thread count.
void normalizeKernelCoverage(const RayAccel& accel, PhotonMap& photons, const CoverageSettings& settings,
                             ThreadPool& pool, Reporter& reporter, CoverageStats* stats = nullptr);

}  // namespace rs
