// Splatting in ray space (DESIGN §9, paper §2 eq. 2 and §5.1): every photon ray traverses
// the occlusion tree as a cylinder of its splat radius h; each visible eye sample y in it
// receives
//     w · f_r(y, −ω, ωo) · Φ · K_h(d⊥) · |n·ω| · V
// where d⊥ is y's distance to the ray's line, K_h the biweight kernel normalised over the
// disc of radius h perpendicular to ω, and V the occlusion mask's visibility at y. Light
// lands in the film layer of the photon's class (direct, indirect, caustic).
#pragma once

#include "film.h"
#include "kdtree_traverse.h"
#include "photons.h"

namespace rs {

class ThreadPool;
class Reporter;
struct Scene;

struct SplatStats {
    TraversalStats traversal;
    uint64_t contributions = 0;  // (photon, eye sample) pairs that received energy
};

// Biweight kernel over the disc of radius h: ∫ K dA = 1.
inline float biweightKernel(float d2, float h2) {
    float x = 1.f - d2 / h2;
    return x <= 0.f ? 0.f : 3.f / (kPi * h2) * x * x;
}

// Adds the photons' light to `film` (direct, indirect and caustic layers; pixel = eye
// sample's pixel index). The result does not depend on the thread count: contributions are
// summed as 64-bit fixed-point integers, whose sum does not depend on order.
void splatPhotons(const Scene& scene, const OcclusionTree& tree, const EyeSamples& samples, const PhotonMap& photons,
                  Film& film, ThreadPool& pool, Reporter& reporter, SplatStats* stats = nullptr);

}  // namespace rs
