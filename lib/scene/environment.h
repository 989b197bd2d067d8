// The environment light (docs/design.md §4): radiance arriving from infinitely far away in every
// direction, as an equirectangular image times a strength, or one colour (a uniform sky). It
// is oriented as Blender's world, so that a Blender user's HDRI looks the same after glTF
// export: the image's centre column lies along +X, the column a quarter in from its left edge
// along −Z (glTF's; Blender's +Y), its top row straight up. The rotation is a Mapping node's Z
// rotation in Blender's world shader: a direction is turned by it about the up axis before the
// image is read, so the sky turns the other way, clockwise seen from above. Directions are
// world space (glTF: +Y up), unit, pointing from the scene towards the sky.
#pragma once

#include <string>
#include <vector>

#include "core/math.h"

namespace rs {

class Environment {
public:
    Environment() = default;  // black: no environment
    static Environment uniform(Vec3 radiance);
    // An equirectangular image, `pixels` row by row from the top, linear RGB radiance in
    // W/(m²·sr) before `strength`. Negative and non-finite values count as 0.
    static Environment image(int width, int height, std::vector<Vec3> pixels, float strength, float rotationRadians);

    bool black() const { return total_ <= 0.0; }
    Vec3 radiance(const Vec3& dir) const;
    // A direction chosen in proportion to luminance × solid angle (uniform over the sphere for
    // a uniform sky); pdf: solid-angle density.
    Vec3 sample(Vec2 u, float& pdf) const;
    float pdf(const Vec3& dir) const;
    // ∫ L dω over the sphere, RGB: times π R², the power it sends through a disc of radius R.
    Vec3 integral() const { return integral_; }

private:
    // (column, row) of the pixel seen in direction `dir`, and the direction at image point (u, v).
    void pixelOf(const Vec3& dir, int& x, int& y) const;
    Vec3 directionAt(float u, float v) const;

    int width_ = 0, height_ = 0;  // 0: uniform
    std::vector<Vec3> pixels_;    // top row first
    Vec3 uniform_{0.f};
    float cosRot_ = 1.f, sinRot_ = 0.f;
    // Sampling: rows by their total weight, then a column within the row; weight = luminance ×
    // sin θ of the pixel's centre.
    std::vector<double> rowCdf_;    // height_ + 1 entries, rowCdf_[0] = 0, last = 1
    std::vector<float> columnCdf_;  // per row, width_ + 1 entries, from 0 to 1
    std::vector<float> weight_;     // per pixel, normalised: sums to 1
    double total_ = 0.0;
    Vec3 integral_{0.f};
};

// Reads an equirectangular environment from an OpenEXR file (R, G, B channels; Y alone as
// grey). Throws Error(Io/Config) naming the file.
Environment loadEnvironment(const std::string& path, float strength, float rotationRadians);

}  // namespace rs
