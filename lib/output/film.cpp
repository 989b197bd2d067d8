// Film buffers and the relative MSE between images.
#include "output/film.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace rs {

const char* layerName(int layer) {
    static const char* names[kLayerCount] = {"direct", "indirect", "caustic", "emission"};
    return names[layer];
}

Film::Film(int w, int h) : width(w), height(h) {
    for (auto& l : layers) l.assign(pixelCount(), Vec3(0.f));
    albedo.assign(pixelCount(), Vec3(0.f));
    normal.assign(pixelCount(), Vec3(0.f));
}

Vec3 Film::beauty(size_t i) const {
    Vec3 sum(0.f);
    for (const auto& l : layers) sum += l[i];
    return sum;
}

std::vector<Vec3> Film::beautyImage() const {
    std::vector<Vec3> out(pixelCount());
    for (size_t i = 0; i < out.size(); ++i) out[i] = beauty(i);
    return out;
}

FixedFilm::FixedFilm(int w, int h) : width(w), height(h) {
    for (auto& b : buffers) b.assign(pixelCount() * 3, 0);
}

int64_t FixedFilm::toFixed(float v) {
    constexpr double kLimit = 1073741824.0;  // 2^30: two such values add without overflow
    const double x = std::clamp(double(v), -kLimit, kLimit) * kScale;
    return v == v ? std::llround(x) : 0;  // a NaN adds nothing
}

void FixedFilm::addSaturating(int64_t& sum, int64_t v) {
    if (__builtin_add_overflow(sum, v, &sum)) sum = v > 0 ? INT64_MAX : INT64_MIN;
}

void FixedFilm::add(const Film& film) {
    RS_CHECK(film.width == width && film.height == height);
    for (int b = 0; b < kBuffers; ++b) {
        const std::vector<Vec3>& from = film.buffer(b);
        int64_t* to = buffers[b].data();
        for (size_t i = 0; i < from.size(); ++i)
            for (int c = 0; c < 3; ++c) addSaturating(to[i * 3 + c], toFixed(from[i][c]));
    }
}

void FixedFilm::add(const FixedFilm& other) {
    RS_CHECK(other.width == width && other.height == height);
    for (int b = 0; b < kBuffers; ++b) {
        if (other.buffers[b].empty()) continue;  // a film of some buffers only (a splat's layers)
        RS_CHECK(other.buffers[b].size() == buffers[b].size());
        for (size_t i = 0; i < buffers[b].size(); ++i) addSaturating(buffers[b][i], other.buffers[b][i]);
    }
}

void FixedFilm::countPhotonPass(const double share[3]) {
    for (int c = 0; c < 3; ++c) photonPasses[c] += std::llround(std::clamp(share[c], 0.0, 1.0) * kScale);
}

void FixedFilm::countFilmPass(bool directInFilm) {
    ++filmPasses;
    if (directInFilm) photonPasses[kDirect] += int64_t(kScale);
}

Film FixedFilm::average(int passes) const {
    Film film(width, height);
    for (int b = 0; b < kBuffers; ++b) {
        const double scale = 1.0 / (b < 3 && photonPasses[b] > 0 ? double(photonPasses[b])
                                                                 : kScale * double(std::max<int64_t>(passes + filmPasses, 1)));
        std::vector<Vec3>& to = film.buffer(b);
        const int64_t* from = buffers[b].data();
        for (size_t i = 0; i < to.size(); ++i)
            to[i] = Vec3(float(double(from[i * 3]) * scale), float(double(from[i * 3 + 1]) * scale),
                         float(double(from[i * 3 + 2]) * scale));
    }
    return film;
}

double relativeMse(const std::vector<Vec3>& a, const std::vector<Vec3>& ref) {
    RS_CHECK(a.size() == ref.size());
    double sum = 0.0;
    for (size_t i = 0; i < a.size(); ++i)
        for (int c = 0; c < 3; ++c) sum += sqr(a[i][c] - ref[i][c]) / (double(ref[i][c]) * ref[i][c] + 1e-2);
    return a.empty() ? 0.0 : sum / (3.0 * double(a.size()));
}

}  // namespace rs
