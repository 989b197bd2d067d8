// Kernel coverage (docs/design.md §8): the share of a photon ray's kernel that lands on a
// surface which may receive it. A kernel is a disc of parallel rays around the photon's own;
// near a concave corner part of the disc starts behind the surface the photon leaves, past a
// convex edge or a thin part it lands on nothing within the cylinder, and on fine geometry on
// samples the receiver rules refuse. That part's light is lost, and more of it the larger the
// kernel. Probes along the disc's rays, distributed as the kernel, measure the share that
// arrives. Where the kernel lands on one plane, the lines that cut it there are found instead
// (KernelEdge), and each sample divides the light it receives by the share of its own kernel on
// their arriving side; elsewhere the photon's flux is divided by the share, so that each photon
// delivers its flux, and a kernel that mostly misses is halved first and measured again
// (kShrinkBelow).
// World space; the probes are Embree rays.
#pragma once

#include <cstdint>

#include "core/stats.h"
#include "splat/kernel_edge.h"

namespace rs {

class RayAccel;
class ThreadPool;
class Reporter;
struct PhotonMap;
struct PhotonRay;

struct CoverageSettings {
    static constexpr int kMaxProbes = 16;  // one Embree packet
    // Rays a photon, distributed as the biweight kernel. On the staircase interior at 180 px,
    // 2 passes, the indirect layer's mean over the path tracer's was 1.028 with 8, 1.025 with
    // 16 and 1.023 with 32 (0.917 with none). At 180×320, 4 passes, two seeds, the beauty's
    // rel. MSE was the same with 8 as with 16 (4.19e-3 against 4.15e-3) and the render 1.15
    // times as fast: the probes were a quarter of its time.
    int probes = 8;
    // A kernel whose coverage is below this is halved once, and measured again. Dividing by the
    // photon's own coverage keeps each photon's flux but moves light within two radii of an
    // edge: the rim gets too little, the band inside it too much (under point_shadows' point
    // light a box's face was 8 % too bright inside, 15–25 % too dark at its rim). A smaller
    // kernel moves it a shorter way. 256 px, 4 passes, beauty rel. MSE: point_shadows 8.99e-5 →
    // 3.07e-5 and 18.4 → 16.3 s; direct_light 1.18e-4 → 5.02e-5; cornell_box 1.71e-3 →
    // 1.73e-3; interior 3.53e-3 → 3.75e-3 in the same time (threshold 0.75: 3.52e-5, 5.83e-5,
    // 1.79e-3, 3.95e-3; halving to 0.9, twice: 1.08e-4, 1.59e-4, 2.38e-3, 5.79e-3).
    static constexpr float kShrinkBelow = 0.6f;
    // The flux is divided by at least this (0: by the coverage however small), and so is a
    // sample's light by its share with kernel edges (KernelEdge). A photon whose
    // kernel lands mostly on nothing (a chandelier's arms, a thin frame) delivers its flux to a
    // small part of it: with 8 probes one arriving multiplies the flux by 8, and these rare,
    // heavy photons are the fireflies. On the staircase (180×320, 8 passes, two seeds against
    // the path tracer at 1024 spp) the brightest pixel's squared difference between the seeds
    // fell from 3.27 to 2.10 (0.5: 1.45) and the beauty rel. MSE from 3.01e-3 to 2.44e-3 (0.5:
    // 2.34e-3). Its bias, the indirect light's mean over the reference's: staircase 1.0035 →
    // 1.0005 (0.5: 0.996); at 256 px, 4 passes, interior 1.001 → 1.000, direct_light, cornell_box
    // and glossy_box unchanged, point_shadows 0.999 → 0.998 (0.5: 0.998, 0.996, 0.998, 0.999,
    // 0.990). Rel. MSE on those scenes changed by under 0.5 %.
    float minCoverage = 0.25f;
    // Counts only the surfaces within PhotonRay::kReceiverWindow radii of x(i), as the splat
    // takes them (SplatSettings::receiverWindow).
    bool receiverWindow = true;
    // Where the kernel lands on one plane: the loss at the samples (KernelEdge), not the photon.
    bool atSamples = true;
    uint64_t seed = 0;       // with the pass: the probes' rotation, a function of (seed, pass, photon)
    uint64_t pass = 0;
};

// Photons probed; with coverage below 1; with none; kernels halved (coverage below
// kShrinkBelow); kernels on one plane, whose loss the samples correct (KernelEdge).
#define RS_COVERAGE_COUNTERS(X)                                                                      \
    X(photons, "coverage_photons") X(partial, "coverage_photons_partial")                            \
    X(uncovered, "coverage_photons_uncovered") X(shrunk, "coverage_photons_shrunk")                  \
    X(atSamples, "coverage_photons_at_samples")
struct CoverageStats {
    RS_COVERAGE_COUNTERS(RS_COUNTER_MEMBER)
    double coverageSum = 0.0;  // sum of the photons' coverage
    void add(const CoverageStats& o) {
        RS_COVERAGE_COUNTERS(RS_COUNTER_ADD)
        coverageSum += o.coverageSum;
    }
    void report(Stats& stats) const {
        RS_COVERAGE_COUNTERS(RS_COUNTER_REPORT)
        stats.setCount("coverage_mean", photons ? coverageSum / double(photons) : 1.0);
    }
};

// Measures one photon ray's kernel coverage c, halves the kernel and measures again where c <
// kShrinkBelow, and divides the flux by max(c, minCoverage) (a photon whose probes all miss
// keeps its flux: nothing measured to divide by). The probes' turn is a function of (seed, pass,
// the ray itself), so a ray's coverage does not depend on which map or thread holds it. The
// splat measures it for the photons that reach an eye sample, just before their light lands.
// With `edge` and settings.atSamples, where the kernel lands on one plane (kernelEdges in
// coverage.cpp), the flux is divided only by the share the edge's lines leave out, and the samples
// correct the rest (edge->lines > 0); elsewhere edge->lines is 0.
void normalizeCoverage(const RayAccel& accel, PhotonRay& ray, const CoverageSettings& settings, CoverageStats& stats,
                       KernelEdge* edge = nullptr);

// normalizeCoverage for every photon ray of the map, their edges (with settings.atSamples) kept
// in photons.edges: a walkthrough's store measures them once for every frame, each the same
// function of the ray as the splat's own measurement.
void normalizeKernelCoverage(const RayAccel& accel, PhotonMap& photons, const CoverageSettings& settings,
                             ThreadPool& pool, Reporter& reporter, CoverageStats* stats = nullptr);

}  // namespace rs
