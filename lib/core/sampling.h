// Random and quasi-random numbers as pure functions of (seed, stage, item index, dimension)
// (docs/design.md §2): never of a thread or of timing. Plus the warps from [0,1)² to directions.
#pragma once

#include <cstdint>

#include "core/math.h"

namespace rs {

enum class Stage : uint32_t { Camera = 1, Path = 2, Photon = 3, Eye = 4, Direct = 5, Coverage = 6, DirectFilm = 7, Probe = 8, Test = 99 };

inline uint64_t mix64(uint64_t z) {  // splitmix64 finaliser
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

// The longest path any stage follows unless told otherwise: segments of a photon path or a
// path-traced path, specular bounces of an eye ray's chain.
constexpr int kDefaultMaxDepth = 32;

// The stream index of sample `index` (< 2^24 a pixel) of pixel `pixel`, for Sampler and hashKey.
constexpr int kSampleIndexBits = 24;
inline uint64_t pixelSampleKey(uint32_t pixel, uint64_t index) { return (uint64_t(pixel) << kSampleIndexBits) ^ index; }

inline uint64_t hashKey(uint64_t seed, Stage stage, uint64_t index, uint64_t dim = 0) {
    uint64_t h = mix64(seed + 0x9e3779b97f4a7c15ull * (uint64_t(stage) + 1));
    h = mix64(h ^ (index + 0x632be59bd9b4e019ull));
    return mix64(h ^ (dim * 0xd6e8feb86659fd93ull + 0x2545f4914f6cdd1dull));
}

inline float toUnitFloat(uint32_t x) {  // [0, 1), 24 bits
    return float(x >> 8) * 0x1p-24f;
}

// Owen scrambling of a 32-bit fixed-point value (Laine–Karras style nested hash).
inline uint32_t reverseBits(uint32_t x) {
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
}
inline uint32_t owenScramble(uint32_t v, uint32_t seed) {
    v = reverseBits(v);
    v ^= v * 0x3d20adeau;
    v += seed;
    v *= (seed >> 16) | 1u;
    v ^= v * 0x05526c56u;
    v ^= v * 0x53a22864u;
    return reverseBits(v);
}

// The first two dimensions of the Sobol sequence (a (0,2)-sequence): point i.
inline uint32_t sobolDim0(uint32_t i) { return reverseBits(i); }
inline uint32_t sobolDim1(uint32_t i) {
    uint32_t v = 1u << 31, r = 0;
    for (; i; i >>= 1, v ^= v >> 1)
        if (i & 1) r ^= v;
    return r;
}

// Owen-scrambled 2D Sobol point `i`, scrambled by `seed`: stratified in every elementary
// interval for power-of-two counts.
inline Vec2 sobol2D(uint32_t i, uint64_t seed) {
    uint32_t s0 = uint32_t(seed), s1 = uint32_t(seed >> 32);
    return {toUnitFloat(owenScramble(sobolDim0(i), s0)), toUnitFloat(owenScramble(sobolDim1(i), s1))};
}

// Per-sample stream: dimension d of item `index` in `stage`.
class Sampler {
public:
    Sampler(uint64_t seed, Stage stage, uint64_t index) : key_(hashKey(seed, stage, index)) {}
    float get1D() { return toUnitFloat(uint32_t(mix64(key_ + 0x9e3779b97f4a7c15ull * ++dim_) >> 32)); }
    Vec2 get2D() { float a = get1D(); return {a, get1D()}; }

private:
    uint64_t key_;
    uint64_t dim_ = 0;
};

// -- Warps ---------------------------------------------------------------------------------

inline Vec3 sampleCosineHemisphere(Vec2 u) {  // local frame, z up; pdf = cosθ/π
    float r = std::sqrt(u.x), phi = 2.f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.f, 1.f - u.x))};
}
inline Vec3 sampleUniformSphere(Vec2 u) {  // pdf = 1/(4π)
    float z = 1.f - 2.f * u.x, r = std::sqrt(std::max(0.f, 1.f - z * z)), phi = 2.f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
inline Vec3 sampleUniformCone(Vec2 u, float cosMax) {  // around +z; pdf = 1/(2π(1−cosMax))
    float z = 1.f - u.x * (1.f - cosMax), r = std::sqrt(std::max(0.f, 1.f - z * z)), phi = 2.f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
inline Vec2 sampleUniformTriangle(Vec2 u) {  // barycentrics (b1, b2), uniform in area
    float s = std::sqrt(u.x);
    return {1.f - s, u.y * s};
}
inline Vec2 sampleUniformDisk(Vec2 u) {  // concentric mapping, unit disc
    Vec2 o = 2.f * u - Vec2(1.f);
    if (o.x == 0.f && o.y == 0.f) return Vec2(0.f);
    float r, theta;
    if (std::abs(o.x) > std::abs(o.y)) { r = o.x; theta = 0.25f * kPi * (o.y / o.x); }
    else { r = o.y; theta = 0.5f * kPi - 0.25f * kPi * (o.x / o.y); }
    return r * Vec2(std::cos(theta), std::sin(theta));
}

inline float powerHeuristic(float pdfA, float pdfB) {
    float a = pdfA * pdfA, b = pdfB * pdfB;
    return a + b > 0.f ? a / (a + b) : 0.f;
}

}  // namespace rs
