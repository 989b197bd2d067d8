#include "scene/environment.h"

#include <OpenEXR/ImfArray.h>
#include <OpenEXR/ImfRgbaFile.h>
#include <stb_image.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/sampling.h"

namespace rs {

namespace {

// Index of the interval of `cdf` (ascending, cdf[0] = 0, last = 1) that holds u, and u's place
// within it, in [0, 1).
template <class T>
size_t pick(const T* cdf, size_t n, double u, double& within) {
    size_t i = size_t(std::upper_bound(cdf, cdf + n + 1, u) - cdf);
    i = std::clamp<size_t>(i, 1, n) - 1;
    while (i + 1 < n && !(cdf[i + 1] > cdf[i])) ++i;  // skip empty intervals
    const double width = cdf[i + 1] - cdf[i];
    within = width > 0.0 ? std::clamp((u - cdf[i]) / width, 0.0, 0x1.fffffep-1) : 0.5;
    return i;
}

}  // namespace

Environment Environment::uniform(Vec3 radiance) {
    Environment e;
    e.uniform_ = glm::max(radiance, Vec3(0.f));
    e.integral_ = 4.f * kPi * e.uniform_;
    e.total_ = double(luminance(e.uniform_));
    return e;
}

Environment Environment::image(int width, int height, std::vector<Vec3> pixels, float strength, float rotationRadians) {
    Environment e;
    e.width_ = width;
    e.height_ = height;
    e.pixels_ = std::move(pixels);
    for (Vec3& p : e.pixels_)
        for (int c = 0; c < 3; ++c) p[c] = std::isfinite(p[c]) && p[c] > 0.f ? p[c] * strength : 0.f;
    e.cosRot_ = std::cos(rotationRadians);
    e.sinRot_ = std::sin(rotationRadians);

    // Weights luminance × sin θ of the pixel's centre; rows by their sums, columns within a row.
    e.weight_.resize(e.pixels_.size());
    e.rowCdf_.assign(size_t(height) + 1, 0.0);
    e.columnCdf_.assign(size_t(height) * (width + 1), 0.f);
    DVec3 integral(0.0);
    for (int y = 0; y < height; ++y) {
        const double sinCentre = std::sin(kPi * (y + 0.5) / height);
        // The solid angle of one pixel of this row: 2π/W · (cos θ0 − cos θ1).
        const double omega = 2.0 * kPi / width * (std::cos(kPi * y / height) - std::cos(kPi * (y + 1.0) / height));
        float* w = &e.weight_[size_t(y) * width];
        double rowSum = 0.0;
        for (int x = 0; x < width; ++x) {
            const Vec3& L = e.pixels_[size_t(y) * width + x];
            integral += DVec3(L) * omega;
            w[x] = float(double(luminance(L)) * sinCentre);
            rowSum += w[x];
        }
        e.rowCdf_[y + 1] = e.rowCdf_[y] + rowSum;
        float* cdf = &e.columnCdf_[size_t(y) * (width + 1)];
        double acc = 0.0;
        for (int x = 0; x < width && rowSum > 0.0; ++x) cdf[x + 1] = float((acc += w[x]) / rowSum);
    }
    e.total_ = e.rowCdf_[height];
    e.integral_ = Vec3(integral);
    if (e.total_ > 0.0) {
        for (double& c : e.rowCdf_) c /= e.total_;
        for (float& w : e.weight_) w = float(double(w) / e.total_);
    }
    return e;
}

Vec3 Environment::directionAt(float u, float v) const {
    const float theta = kPi * v, phi = 2.f * kPi * (u - 0.5f);
    const Vec3 e(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
    // Turned back by −rotation about +Y: the world direction whose lookup is this image point.
    return {cosRot_ * e.x - sinRot_ * e.z, e.y, sinRot_ * e.x + cosRot_ * e.z};
}

void Environment::pixelOf(const Vec3& dir, int& x, int& y) const {
    // Turned by +rotation about +Y (Blender's +Z), as the Mapping node turns its vector.
    const Vec3 e(cosRot_ * dir.x + sinRot_ * dir.z, dir.y, -sinRot_ * dir.x + cosRot_ * dir.z);
    const float u = 0.5f + std::atan2(e.z, e.x) / (2.f * kPi);
    const float v = std::acos(std::clamp(e.y, -1.f, 1.f)) / kPi;
    x = std::clamp(int(u * float(width_)), 0, width_ - 1);
    y = std::clamp(int(v * float(height_)), 0, height_ - 1);
}

Vec3 Environment::radiance(const Vec3& dir) const {
    if (width_ == 0) return uniform_;
    int x, y;
    pixelOf(dir, x, y);
    return pixels_[size_t(y) * width_ + x];
}

Vec3 Environment::sample(Vec2 u, float& pdf) const {
    pdf = 0.f;
    if (black()) return Vec3(0.f, 1.f, 0.f);
    if (width_ == 0) {
        pdf = 1.f / (4.f * kPi);
        return sampleUniformSphere(u);
    }
    double fy, fx;
    const size_t y = pick(rowCdf_.data(), size_t(height_), double(u.x), fy);
    const size_t x = pick(&columnCdf_[y * (width_ + 1)], size_t(width_), double(u.y), fx);
    // Kept off the pixel's borders, where rounding could carry the direction into a neighbour;
    // the pdf is then read back from the direction, so that sample, pdf and radiance agree.
    fx = std::clamp(fx, 1e-4, 1.0 - 1e-4);
    fy = std::clamp(fy, 1e-4, 1.0 - 1e-4);
    const Vec3 d = directionAt(float((double(x) + fx) / width_), float((double(y) + fy) / height_));
    pdf = this->pdf(d);
    return d;
}

float Environment::pdf(const Vec3& dir) const {
    if (black()) return 0.f;
    if (width_ == 0) return 1.f / (4.f * kPi);
    const float sinTheta = std::sqrt(dir.x * dir.x + dir.z * dir.z);  // exact near the poles, unlike √(1 − y²)
    if (!(sinTheta > 0.f)) return 0.f;
    int x, y;
    pixelOf(dir, x, y);
    return float(double(weight_[size_t(y) * width_ + x]) * double(width_) * double(height_) / (2.0 * kPi * kPi * sinTheta));
}

namespace {

// Whether the file starts as a Radiance picture does ("#?RADIANCE" or "#?RGBE").
bool isRadiance(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    char head[10] = {};
    in.read(head, sizeof head);
    const std::string start(head, size_t(in.gcount()));
    return start.rfind("#?RADIANCE", 0) == 0 || start.rfind("#?RGBE", 0) == 0;
}

// A Radiance .hdr (RGBE, flat or run-length scanlines) by stb_image, top row first as in EXR.
void readRadiance(const std::string& path, int& width, int& height, std::vector<Vec3>& pixels) {
    int channels = 0;
    float* data = stbi_loadf(path.c_str(), &width, &height, &channels, 3);
    if (!data) throw Error(ErrorKind::Io, path + ": not a Radiance .hdr image the environment can read (" + stbi_failure_reason() + ")");
    pixels.resize(size_t(width) * size_t(height));
    for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = Vec3(data[3 * i], data[3 * i + 1], data[3 * i + 2]);
    stbi_image_free(data);
}

void readOpenExr(const std::string& path, int& width, int& height, std::vector<Vec3>& pixels) {
    try {
        Imf::RgbaInputFile file(path.c_str());
        const Imath::Box2i dw = file.dataWindow();
        width = dw.max.x - dw.min.x + 1;
        height = dw.max.y - dw.min.y + 1;
        Imf::Array2D<Imf::Rgba> rgba(height, width);
        file.setFrameBuffer(&rgba[0][0] - dw.min.x - dw.min.y * width, 1, size_t(width));
        file.readPixels(dw.min.y, dw.max.y);
        pixels.resize(size_t(width) * height);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const Imf::Rgba& p = rgba[y][x];
                pixels[size_t(y) * width + x] = Vec3(float(p.r), float(p.g), float(p.b));
            }
    } catch (const std::exception& e) {
        throw Error(ErrorKind::Io, path + ": not an OpenEXR or Radiance .hdr image the environment can read (" + e.what() + ")");
    }
}

}  // namespace

Environment loadEnvironment(const std::string& path, float strength, float rotationRadians) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(ErrorKind::Io, path + ": no such file");
    int width = 0, height = 0;
    std::vector<Vec3> pixels;
    if (isRadiance(path))
        readRadiance(path, width, height, pixels);
    else
        readOpenExr(path, width, height, pixels);
    for (const Vec3& p : pixels)
        if (!isFinite(p) || p.x < 0.f || p.y < 0.f || p.z < 0.f)
            throw Error(ErrorKind::Config, path + ": the environment image has a negative or non-finite pixel");
    if (width != 2 * height)
        throw Error(ErrorKind::Config, path + ": " + std::to_string(width) + "x" + std::to_string(height) +
                                           " pixels; an equirectangular environment is twice as wide as high");
    Environment env = Environment::image(width, height, std::move(pixels), strength, rotationRadians);
    if (env.black()) throw Error(ErrorKind::Config, path + ": the environment image is black");
    return env;
}

}  // namespace rs
