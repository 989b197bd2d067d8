// Film buffers and the relative MSE between images.
#include "output/film.h"

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

void Film::add(const Film& o) {
    RS_CHECK(o.width == width && o.height == height);
    for (int l = 0; l < kLayerCount; ++l)
        for (size_t i = 0; i < pixelCount(); ++i) layers[l][i] += o.layers[l][i];
    for (size_t i = 0; i < pixelCount(); ++i) {
        albedo[i] += o.albedo[i];
        normal[i] += o.normal[i];
    }
}

void Film::scale(float s) {
    for (auto& l : layers)
        for (Vec3& v : l) v *= s;
    for (Vec3& v : albedo) v *= s;
    for (Vec3& v : normal) v *= s;
}

double relativeMse(const std::vector<Vec3>& a, const std::vector<Vec3>& ref) {
    RS_CHECK(a.size() == ref.size());
    double sum = 0.0;
    for (size_t i = 0; i < a.size(); ++i)
        for (int c = 0; c < 3; ++c) sum += sqr(a[i][c] - ref[i][c]) / (double(ref[i][c]) * ref[i][c] + 1e-2);
    return a.empty() ? 0.0 : sum / (3.0 * double(a.size()));
}

}  // namespace rs
