// Texture (texture.h): the mip chain's box filter and the lookups.
#include "scene/texture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace rs {

float srgbToLinear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float c) {
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.f / 2.4f) - 0.055f;
}

namespace {

// 8-bit sRGB: the linear value of each code, and the midpoints between neighbours' linear values
// (a linear value encodes to the code nearest to it in linear terms, so a level's mean stays the
// mean of the level above it to within half a step).
struct Srgb8 {
    static constexpr int kBuckets = 4096;
    std::array<float, 256> toLinear;
    std::array<float, 256> unit;      // code / 255: alpha and data
    std::array<float, 256> midpoint;  // [255]: infinity
    // The code of the bucket's lowest value, x in [k, k + 1) / kBuckets. A bucket (1/4096) is
    // narrower than the closest two midpoints (1/(255 · 12.92) apart, near 0), so x lies past at
    // most one more midpoint than the bucket's start.
    std::array<uint8_t, kBuckets + 1> bucketStart;
    Srgb8() {
        for (int k = 0; k < 256; ++k) toLinear[size_t(k)] = srgbToLinear(float(k) / 255.f);
        for (int k = 0; k < 256; ++k) unit[size_t(k)] = float(k) / 255.f;
        for (int k = 0; k < 255; ++k) midpoint[size_t(k)] = 0.5f * (toLinear[size_t(k)] + toLinear[size_t(k) + 1]);
        midpoint[255] = std::numeric_limits<float>::infinity();
        for (int k = 0; k <= kBuckets; ++k)
            bucketStart[size_t(k)] = uint8_t(std::upper_bound(midpoint.begin(), midpoint.end(), float(k) / kBuckets) - midpoint.begin());
    }
    // The code whose linear value is nearest to x in [0, 1] (the number of midpoints ≤ x).
    uint8_t encode(float x) const {
        const int code = bucketStart[size_t(x * float(kBuckets))];
        return uint8_t(code + (midpoint[size_t(code)] <= x ? 1 : 0));
    }
};
const Srgb8 kSrgb8;

// 16-bit sRGB: the linear value of each code (256 KB, made on first use: 16-bit images are rare).
const float* srgb16ToLinear() {
    static const std::vector<float> table = [] {
        std::vector<float> t(65536);
        for (size_t k = 0; k < t.size(); ++k) t[k] = srgbToLinear(float(k) / 65535.f);
        return t;
    }();
    return table.data();
}

// One channel value of type T (uint8_t or uint16_t) to linear and back; channel 3 is alpha.
template <class T>
struct Codec {
    static constexpr float kMax = float((1u << (8 * sizeof(T))) - 1u);
    bool srgb;
    float decode(T v, int c) const {
        if constexpr (sizeof(T) == 1) return !srgb || c == 3 ? kSrgb8.unit[v] : kSrgb8.toLinear[v];
        if (!srgb || c == 3) return float(v) / kMax;
        return srgb16ToLinear()[v];
    }
    T encode(float x, int c) const {
        x = std::clamp(x, 0.f, 1.f);
        if (!srgb || c == 3) return T(x * kMax + 0.5f);
        if constexpr (sizeof(T) == 1) return kSrgb8.encode(x);
        return T(linearToSrgb(x) * kMax + 0.5f);
    }
};

// A box filter from n texels onto m ≤ n: output i averages the source span [i·n/m, (i+1)·n/m),
// texels cut by its ends weighted by the part inside, so every source texel counts as much in
// total and a level's mean is the mean of the level above (any size, not only powers of two).
struct BoxTaps {
    struct Tap {
        int source;
        float weight;
    };
    std::vector<Tap> taps;
    std::vector<int> first;  // output i's taps: [first[i], first[i + 1])
    BoxTaps(int n, int m) {
        const double scale = double(n) / double(m);
        for (int i = 0; i < m; ++i) {
            first.push_back(int(taps.size()));
            const double a = i * scale, b = (i + 1) * scale;
            for (int k = int(std::floor(a)); k < n && double(k) < b; ++k) {
                const double w = std::min(b, double(k + 1)) - std::max(a, double(k));
                if (w > 1e-9) taps.push_back({k, float(w / scale)});
            }
        }
        first.push_back(int(taps.size()));
    }
};

}  // namespace

Texture::Texture(std::string name_, int width, int height, const uint8_t* rgba, bool srgb, bool hasAlpha, bool withMips)
    : name(std::move(name_)), srgb_(srgb), hasAlpha_(hasAlpha) {
    layOutLevels(width, height);
    texels8_.resize(4 * (levels_.back().offset + 1));
    std::copy(rgba, rgba + 4 * size_t(width) * size_t(height), texels8_.begin());
    if (withMips) buildMipChain();
}

Texture::Texture(std::string name_, int width, int height, const uint16_t* rgba, bool srgb, bool hasAlpha, bool withMips)
    : name(std::move(name_)), srgb_(srgb), hasAlpha_(hasAlpha) {
    layOutLevels(width, height);
    texels16_.resize(4 * (levels_.back().offset + 1));
    std::copy(rgba, rgba + 4 * size_t(width) * size_t(height), texels16_.begin());
    if (withMips) buildMipChain();
}

void Texture::buildMipChain() {
    if (texels16_.empty()) buildMips(texels8_);
    else buildMips(texels16_);
}

// Each level half the one above (rounded down, at least 1) until 1 × 1.
void Texture::layOutLevels(int width, int height) {
    RS_CHECK(width > 0 && height > 0);
    size_t offset = 0;
    for (;;) {
        levels_.push_back({width, height, offset});
        offset += size_t(width) * size_t(height);
        if (width == 1 && height == 1) break;
        width = std::max(1, width / 2);
        height = std::max(1, height / 2);
    }
}

// Level l from level l − 1 by the box filter in linear values (sRGB decoded), so that a fine
// pattern of black and white averages to the grey it looks like from afar. Each level is filtered
// from the unrounded values of the one above (kept in `above`, a quarter of level 0's texels in
// floats at most), so that rounding to 8 bits happens once a level instead of piling up.
template <class T>
void Texture::buildMips(std::vector<T>& texels) {
    const Codec<T> codec{srgb_};
    std::vector<float> above, below;
    for (size_t l = 1; l < levels_.size(); ++l) {
        const Level& from = levels_[l - 1];
        const Level& to = levels_[l];
        const BoxTaps tx(from.width, to.width), ty(from.height, to.height);
        std::vector<float> decoded(l == 1 ? 4 * size_t(from.width) : 0);
        below.assign(4 * size_t(to.width) * size_t(to.height), 0.f);
        // Row r of the level above in linear values: decoded from the texels (level 0) or kept.
        auto sourceRow = [&](int r) -> const float* {
            if (l > 1) return &above[4 * size_t(r) * size_t(from.width)];
            const T* src = &texels[4 * (from.offset + size_t(r) * size_t(from.width))];
            for (size_t k = 0; k < decoded.size(); ++k) decoded[k] = codec.decode(src[k], int(k & 3));
            return decoded.data();
        };
        if (from.width == 2 * to.width && from.height == 2 * to.height) {
            // Both sides halve: each texel averages a 2 × 2 block (most levels of most images).
            std::vector<float> upper(4 * size_t(from.width));
            for (int j = 0; j < to.height; ++j) {
                const float* a = sourceRow(2 * j);
                std::copy(a, a + upper.size(), upper.begin());
                const float* b = sourceRow(2 * j + 1);
                float* sum = &below[4 * size_t(j) * size_t(to.width)];
                for (size_t i = 0; i < 4 * size_t(to.width); i += 4)
                    for (size_t c = 0; c < 4; ++c)
                        sum[i + c] = 0.25f * ((upper[2 * i + c] + upper[2 * i + 4 + c]) + (b[2 * i + c] + b[2 * i + 4 + c]));
            }
        } else {
            for (int j = 0; j < to.height; ++j) {
                float* sum = &below[4 * size_t(j) * size_t(to.width)];
                for (int t = ty.first[size_t(j)]; t < ty.first[size_t(j) + 1]; ++t) {
                    const float* row = sourceRow(ty.taps[size_t(t)].source);
                    const float wy = ty.taps[size_t(t)].weight;
                    for (int i = 0; i < to.width; ++i)
                        for (int s = tx.first[size_t(i)]; s < tx.first[size_t(i) + 1]; ++s) {
                            const float w = wy * tx.taps[size_t(s)].weight;
                            const float* in = &row[4 * size_t(tx.taps[size_t(s)].source)];
                            for (int c = 0; c < 4; ++c) sum[4 * size_t(i) + size_t(c)] += w * in[c];
                        }
                }
            }
        }
        T* dst = &texels[4 * to.offset];
        for (size_t k = 0; k < below.size(); ++k) dst[k] = codec.encode(below[k], int(k & 3));
        std::swap(above, below);
    }
}

Vec4 Texture::texel(int level, int x, int y) const {
    const Level& L = levels_[size_t(level)];
    const size_t i = 4 * (L.offset + size_t(y) * size_t(L.width) + size_t(x));
    if (!texels16_.empty()) {
        const Codec<uint16_t> codec{srgb_};
        const uint16_t* p = &texels16_[i];
        return Vec4(codec.decode(p[0], 0), codec.decode(p[1], 1), codec.decode(p[2], 2), codec.decode(p[3], 3));
    }
    const uint8_t* p = &texels8_[i];
    const auto& colour = srgb_ ? kSrgb8.toLinear : kSrgb8.unit;
    return Vec4(colour[p[0]], colour[p[1]], colour[p[2]], kSrgb8.unit[p[3]]);
}

Vec4 Texture::bilinear(int level, Vec2 uv) const {
    const int w = levels_[size_t(level)].width, h = levels_[size_t(level)].height;
    const float x = (uv.x - std::floor(uv.x)) * float(w) - 0.5f;
    const float y = (uv.y - std::floor(uv.y)) * float(h) - 0.5f;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const float fx = x - float(x0), fy = y - float(y0);
    auto at = [&](int i, int j) { return texel(level, ((i % w) + w) % w, ((j % h) + h) % h); };
    return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
           fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

Vec4 Texture::sample(Vec2 uv, float lod) const {
    if (!(lod > 0.f)) return bilinear(0, uv);  // also NaN
    const float last = float(levels_.size() - 1);
    if (lod >= last) return bilinear(int(last), uv);
    const int l = int(lod);
    const float f = lod - float(l);
    const Vec4 a = bilinear(l, uv);
    return f > 0.f ? (1.f - f) * a + f * bilinear(l + 1, uv) : a;
}

float Texture::lodOf(float uvFootprint) const {
    if (!(uvFootprint > 0.f)) return 0.f;
    return std::log2(uvFootprint * std::sqrt(float(width()) * float(height())));
}

int Texture::texelAt(Vec2 uv) const {
    const int w = width(), h = height();
    const float fx = uv.x - std::floor(uv.x), fy = uv.y - std::floor(uv.y);
    const int x = std::min(int(fx * float(w)), w - 1), y = std::min(int(fy * float(h)), h - 1);
    return y * w + x;
}

float Texture::alphaAt(int index) const {
    if (!hasAlpha_) return 1.f;
    return texels16_.empty() ? float(texels8_[4 * size_t(index) + 3]) / 255.f
                             : float(texels16_[4 * size_t(index) + 3]) / 65535.f;
}

}  // namespace rs
