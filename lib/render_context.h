// What every stage of a render is handed (render.cpp builds it once): the scene and what was
// built from it, the image size, the settings, and where work, progress and figures go.
#pragma once

#include "config.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/stats.h"
#include "ranks.h"

namespace rs {

class RayAccel;
class LightSampler;
struct Camera;
struct Scene;

struct RenderContext {
    const Scene& scene;
    const RayAccel& accel;
    const LightSampler& lights;
    const Camera& camera;
    int width, height;
    const RenderConfig& cfg;
    ThreadPool& pool;
    Reporter& reporter;
    Stats& stats;
    Ranks& ranks;
};

// What one rank renders of one pass: share `share` of `shares` equal parts of its photons
// (splat) or rows (path); the eye pass's own light (emission, sampled direct light, albedo,
// normal) comes from share 0 alone.
struct PassShare {
    int pass = 0;
    int share = 0, shares = 1;
};

// Every rank agrees at this point (render.cpp): returns rank 0's `more`, or throws where another
// rank failed (it says why).
bool agreeOrStop(Ranks& ranks, bool more);

}  // namespace rs
