// A photon kernel's edges (docs/design.md §8, "At the samples"): the lines that cut a kernel
// landing on one plane, by which the samples it reaches divide their light. coverage.h finds
// them; a walkthrough's store keeps them beside its photons (photons.h).
#pragma once

#include "core/math.h"

namespace rs {

// Where a photon's kernel is cut, for the samples it reaches (normalizeCoverage). Dividing the
// photon's flux by the share c of its kernel that arrives keeps the photon's flux but not the light
// at each place: near a face's rim a sample's light comes from photons whose kernels lose less
// than its own would, so the rim came out too dark and the band inside it too bright (under
// point_shadows' point light 5–10 % either way at the kernel scale 0.5). Dividing each sample's
// light by the share of a kernel centred on the sample that arrives is right wherever the loss is
// fixed in the scene, the same for every photon near it: a face's edge, a corner. On a plane the
// loss is cut off by straight lines, so a photon's kernel carries up to two:
//     sample y receives its light × 1 / max(Π_k G(t0_k + e_k·(y − x(i−1))), minCoverage)
// with e_k ⊥ ω towards the side that arrives (in 1/radius) and G(t) the share of the biweight
// kernel on the side of a line at t radii from its centre.
struct KernelEdge {
    int lines = 0;
    Vec3 e[2] = {Vec3(0.f), Vec3(0.f)};
    float t0[2] = {1.f, 1.f};
    // A kernel lands on one plane when every probe that arrives lies within this share of the
    // radius of the hit's plane, its normal within 25.8°.
    static constexpr float kPlaneTolerance = 0.05f, kPlaneCos = 0.9f;
    // G(t): the share of the unit biweight kernel on the side x > −t of a line (G(−1) = 0, G(1) = 1).
    static float share(float t);
    static float shareInverse(float c);
    // Π_k G(t0_k + across_k), across_k = e_k·(y − x(i−1)).
    float shareAt(const float across[2]) const {
        float g = 1.f;
        for (int k = 0; k < lines; ++k) g *= share(t0[k] + across[k]);
        return g;
    }
};

}  // namespace rs
