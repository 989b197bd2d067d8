// Film: the image being rendered, kept as separate light-transport layers (docs/design.md §8, §10)
// whose sum is the beauty image, plus first-hit albedo and normal for denoisers.
// Raster space: pixel (x, y) covers [x, x+1) × [y, y+1), y down, centre at +0.5.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/math.h"

namespace rs {

enum Layer { kDirect = 0, kIndirect, kCaustic, kEmission, kLayerCount };
const char* layerName(int layer);

struct Film {
    int width = 0, height = 0;
    std::vector<Vec3> layers[kLayerCount];
    std::vector<Vec3> albedo, normal;

    Film() = default;
    Film(int w, int h);
    size_t pixelCount() const { return size_t(width) * height; }
    // Buffer b of the FixedFilm order: the layers, then albedo, then normal.
    std::vector<Vec3>& buffer(int b) { return b < kLayerCount ? layers[b] : b == kLayerCount ? albedo : normal; }
    const std::vector<Vec3>& buffer(int b) const { return const_cast<Film*>(this)->buffer(b); }
    Vec3 beauty(size_t i) const;
    std::vector<Vec3> beautyImage() const;
};

// The sum of a render's passes, in 64-bit fixed point (2^-32 resolution; a pixel's sum saturates
// at ±2^31): integer sums do not depend on their order, so passes, threads and the
// ranks of a distributed render (docs/design.md §11) can add their parts in any order and
// the image is the same to the bit.
struct FixedFilm {
    static constexpr double kScale = 4294967296.0;  // 2^32
    int width = 0, height = 0;
    // Per buffer (the layers, then albedo, then normal): pixel × rgb.
    static constexpr int kBuffers = kLayerCount + 2;
    std::vector<int64_t> buffers[kBuffers];
    // Per photon layer (direct, indirect, caustic): the passes counted, each by the share of its
    // photons it splatted (fixed point; a pass cut short by a time limit counts its share). No
    // pass counted: the layers are averaged over the passes, as the others.
    int64_t photonPasses[3] = {0, 0, 0};
    // Passes of the eye film alone (the direct film's samples, no photons: docs/design.md §9),
    // beside the whole passes: the buffers no photon class counts are averaged over both.
    int64_t filmPasses = 0;

    FixedFilm() = default;
    FixedFilm(int w, int h);
    // Counts a pass that splatted `share[c]` (0..1] of each photon class's light.
    void countPhotonPass(const double share[3]);
    // Counts a pass of the eye film alone; `directInFilm`: the direct layer is the film's (light
    // sampling, no direct photons), and counts it too.
    void countFilmPass(bool directInFilm);
    size_t pixelCount() const { return size_t(width) * height; }
    static int64_t toFixed(float v);
    static void addSaturating(int64_t& sum, int64_t v);
    void add(const FixedFilm& other);  // its buffers that it holds (all, or a splat's layers)
    void add(const Film& film);  // every buffer of `film`, pixelwise
    // The average of `passes` passes, as a float film (the photon layers over their counted
    // passes, where counted; the others over `passes` and the film passes).
    Film average(int passes) const;
};

// Relative MSE of `a` against the reference `ref`, per channel: mean of (a − r)² / (r² + ε),
// ε = 0.01 keeping dark pixels from dominating. The figure the tests and benchmarks report.
double relativeMse(const std::vector<Vec3>& a, const std::vector<Vec3>& ref);

}  // namespace rs
