// Film: the image being rendered, kept as separate light-transport layers (docs/design.md §8, §10)
// whose sum is the beauty image, plus first-hit albedo and normal for denoisers.
// Raster space: pixel (x, y) covers [x, x+1) × [y, y+1), y down, centre at +0.5.
#pragma once

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
    Vec3 beauty(size_t i) const;
    std::vector<Vec3> beautyImage() const;
    void add(const Film& other);  // pixelwise sum of every buffer
    void scale(float s);
};

// Relative MSE of `a` against the reference `ref`, per channel: mean of (a − r)² / (r² + ε),
// ε = 0.01 keeping dark pixels from dominating. The figure the tests and benchmarks report.
double relativeMse(const std::vector<Vec3>& a, const std::vector<Vec3>& ref);

}  // namespace rs
