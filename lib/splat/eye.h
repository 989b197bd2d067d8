// Eye pass (docs/design.md §4): camera rays traced with Embree; S stratified samples a pixel;
// directly seen emitters go to the film's emission layer; specular chains (glass, mirror)
// are followed with Fresnel-chosen branches; at the first non-specular hit an eye sample is
// stored. Eye samples are the only places where photon energy lands (docs/design.md §8). With direct
// light by sampling, each eye sample also estimates its direct light there (direct.h).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/sampling.h"
#include "occlusion/eye_samples.h"
#include "output/film.h"
#include "core/math.h"

namespace rs {

class RayAccel;
class LightSampler;
struct Camera;
struct Scene;
class Reporter;

struct EyePassSettings {
    int width = 500, height = 500;
    int spp = 4;              // S: stratified camera samples a pixel (paper: 500×500×4)
    int firstSample = 0;      // this pass's samples are [firstSample, firstSample + S) of each pixel's sequence
    int maxSpecularDepth = kDefaultMaxDepth;  // longest specular chain followed
    int directSamples = 0;    // > 0: direct light by that many light samples a point, at every eye sample or in the film
    // D > 0: a direct film of D camera samples a pixel, apart from the receivers, takes the
    // emission, the direct light, albedo and normal; this pass's are [firstDirectSample,
    // firstDirectSample + D) of each pixel's own sequence. 0: the receivers' samples take them.
    int directSpp = 0;
    int firstDirectSample = 0;
    uint64_t seed = 0;
    bool measureFilmNoise = false;  // EyePass::filmNoise, where there is a direct film of D ≥ 2
    // EyePass::filmSpread, where there is a direct film of D ≥ 2 (the first pass, for filmExtraSamples).
    bool measureFilmSpread = false;
    // Per pixel, film samples this pass takes beyond the D (filmExtraSamples), from a sequence of
    // their own: pass p's (p = firstDirectSample / D) are [p·kExtraBlock, p·kExtraBlock + extra)
    // of it. Null: none.
    const std::vector<uint16_t>* extraFilm = nullptr;
};

// Film samples beyond the D a pixel takes where the first pass's film found its light spread
// (docs/design.md §4). Pixel p takes max(D, spread_p / λ) (Neyman's allocation, above the D
// every pixel takes), λ·D being kSpreadOverMean times the image's mean spread, at most
// kExtraMultiple · D, and all of them together at most kExtraShare · D a pixel. Under a point
// light the film's error is all at the edges of objects and shadows, a pixel in seventy: at
// 500 px the point lights take 4 % more samples, which remove four fifths of the film's variance
// (as the spread measures it). A film whose light is spread more evenly (an area light's or the
// sky's noise, a room's) takes next to none: at twice the mean instead, the daylight room took a
// quarter more samples for 2 % less error (docs/performance.md).
struct FilmExtra {
    static constexpr double kSpreadOverMean = 16.0;
    static constexpr int kExtraMultiple = 8;
    static constexpr double kExtraShare = 0.25;
    static constexpr int kExtraBlock = 1024;  // samples of the extra sequence a pass, at most
};
// `spread`: EyePass::filmSpread; D the film's samples a pixel and pass. Deterministic: summed in
// pixel order. `removed`, if given: the share of the film's variance (by the samples' spread)
// the extra samples take away, and the extra samples over the D of every pixel.
std::vector<uint16_t> filmExtraSamples(const std::vector<float>& spread, int directSpp, double* removed = nullptr);

struct EyePass {
    EyeSamples samples;  // in pixel order, then sample order
    // Emission layer (emitters seen through specular chains), albedo, normal, and with
    // directSamples the direct layer (light sampling at each of the film's samples, or at each
    // eye sample, weighted by it).
    Film film;
    // With measureFilmNoise: per pixel, the variance of the direct film's light (emission and
    // direct), estimated as (mean of its first half of samples − mean of its second)² / 4.
    std::vector<Vec3> filmNoise;
    // With measureFilmSpread: per pixel, √(Σ_c s_c² / (μ_c² + 0.01)), s_c² the variance of one
    // film sample's light (emission and direct) in channel c, μ_c their mean.
    std::vector<float> filmSpread;
};

// `lights` is needed only with settings.directSamples > 0.
EyePass traceEyePass(const Scene& scene, const RayAccel& accel, const LightSampler* lights, const Camera& camera,
                     const EyePassSettings& settings, ThreadPool& pool, Reporter& reporter);

// What an eye pass of `settings` would take, in seconds: a pilot of one row in kPilotRows is
// traced and timed, its samples thrown away. Under a time limit the first pass sizes its direct
// film by it (splat_pass.cpp), so that an image larger than the limit allows still ends in time.
struct EyePassCost {
    static constexpr int kPilotRows = 64;
    double receivers = 0.0, film = 0.0;  // the eye samples' part and the direct film's
};
EyePassCost estimateEyePass(const Scene& scene, const RayAccel& accel, const LightSampler* lights, const Camera& camera,
                            const EyePassSettings& settings, ThreadPool& pool);
// The camera samples a pixel of an eye pass of `cost` (at S = spp eye samples and D = directSpp
// film samples) that fit `budget` seconds: S and D where they fit; else the film's, halved from
// the largest power of two below D, down to 2; then, where that is not enough, the eye
// samples', so, down to 1.
struct EyePassSize {
    int spp = 0, directSpp = 0;
};
EyePassSize eyePassWithin(const EyePassCost& cost, double budget, int spp, int directSpp);

}  // namespace rs
