// Direct light at a non-specular surface point, shared by the path tracer (one sample a
// vertex) and the eye pass of the splat methods (--direct sample: N samples an eye sample).
// Light sampling (next-event estimation) and BSDF sampling are combined with the power
// heuristic; punctual lights are delta and taken by light sampling alone. Light that
// reaches the point only through a specular surface is not direct: the shadow ray is
// blocked, and a BSDF-sampled ray that meets glass or a mirror first brings nothing here
// (the path tracer follows it on; the splat methods get it from caustic photons).
// World space; radiance in W/(m²·sr).
#pragma once

#include "scene/accel.h"
#include "scene/bsdf.h"
#include "scene/lights.h"

namespace rs {

// One light sample from `sp`: f · Li · |cos| / pdf, MIS-weighted against BSDF sampling for
// area lights (`mis`; without it the light samples take the whole weight), 0 when shadowed.
// uChoice picks the light, u the point on it.
Vec3 sampleLightDirect(const RayAccel& accel, const LightSampler& lights, const SurfacePoint& sp, const Bsdf& bsdf,
                       const Vec3& wo, float uChoice, Vec2 u, bool mis = true);

// The MIS weight of emitted light found by a BSDF-sampled ray from `from` (solid-angle pdf
// `bsdfPdf`) hitting the emitter at `hit`: the other half of sampleLightDirect's weight.
float emitterHitWeight(const LightSampler& lights, float bsdfPdf, const Vec3& from, const SurfacePoint& hit);

// The environment's radiance along `dir` met by a ray that left the scene, MIS-weighted as
// emitterHitWeight does for a BSDF-sampled ray (solid-angle pdf `bsdfPdf`); `bsdfPdf` 0: a
// ray no light sampling could have found (a camera ray, a specular bounce), weight 1. Black
// without an environment.
Vec3 environmentSeen(const LightSampler& lights, float bsdfPdf, const Vec3& dir);

// Direct light leaving `sp` towards wo, averaged over n stratified light samples and n BSDF
// samples, MIS-combined. `scramble` and `sampler` make it a pure function of the caller's
// (seed, pixel, sample).
Vec3 estimateDirect(const RayAccel& accel, const LightSampler& lights, const SurfacePoint& sp, const Bsdf& bsdf,
                    const Vec3& wo, int n, uint64_t scramble, class Sampler& sampler);

// estimateDirect for one of a pixel's many samples, its n light samples stratified across the
// pixel's samples: light sample k of the pixel's sample `index` is point index·n + k of a
// pixel-wide 2D Sobol sequence scrambled by `scramble` (walked in a shuffled order, apart from
// the camera's), whose first number both chooses the light and, rescaled, places the point on
// it (LightSampler::withinChoice): each light gets a stratified share of the points.
Vec3 estimateDirectAcrossSamples(const RayAccel& accel, const LightSampler& lights, const SurfacePoint& sp,
                                 const Bsdf& bsdf, const Vec3& wo, int n, uint64_t scramble, uint32_t index,
                                 class Sampler& sampler);

}  // namespace rs
