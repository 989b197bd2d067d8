// The reference path tracer (docs/design.md §8 "path"): the ground truth the tests and the quality
// study compare against. Unidirectional, next-event estimation with MIS (power heuristic)
// for area lights, punctual lights by NEE alone, Russian roulette, box pixel filter with
// Owen-scrambled Sobol pixel positions. Each pixel sample's numbers are a function of
// (seed, pixel, sample index): the image does not depend on the thread count.
#pragma once

#include "core/sampling.h"
#include "scene/accel.h"
#include "scene/camera.h"
#include "output/film.h"
#include "scene/lights.h"
#include "core/log.h"
#include "core/parallel.h"

namespace rs {

struct RayCone;

struct PathSettings {
    int width = 500, height = 500;
    int firstSample = 0;  // sample indices [firstSample, firstSample + spp) of every pixel
    int spp = 16;
    int maxDepth = kDefaultMaxDepth;
    uint64_t seed = 0;
    int rowBegin = 0, rowEnd = 0;  // the rows to render (0, 0: all); the others stay black
};

// Renders one pass; the film holds the average over the pass's samples. Layers split the
// light by its last path segments as the photon classes do (docs/design.md §7): emission seen
// directly (through specular chains), direct, caustic (light → specular+ → first diffuse
// vertex), indirect.
Film renderPathPass(const Scene& scene, const RayAccel& accel, const LightSampler& lights, const Camera& camera,
                    const PathSettings& settings, ThreadPool& pool, Reporter& reporter);

// Radiance along one camera ray, split into layers (for tests: analytic checks). `cone`: the
// ray's footprint for texture filtering (ray_cone.h); a point by default.
struct PathRadiance {
    Vec3 layer[kLayerCount] = {};
    Vec3 albedo{0.f}, normal{0.f};
    Vec3 total() const { return layer[0] + layer[1] + layer[2] + layer[3]; }
};
PathRadiance tracePath(const Scene& scene, const RayAccel& accel, const LightSampler& lights, Vec3 origin,
                       Vec3 dir, int maxDepth, class Sampler& sampler, RayCone cone);
PathRadiance tracePath(const Scene& scene, const RayAccel& accel, const LightSampler& lights, Vec3 origin,
                       Vec3 dir, int maxDepth, class Sampler& sampler);

}  // namespace rs
