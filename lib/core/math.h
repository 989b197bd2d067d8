// Small math vocabulary on top of GLM: vectors, bounds, orthonormal frames.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#define GLM_FORCE_XYZW_ONLY
#include <glm/glm.hpp>

namespace rs {

using Vec2 = glm::vec2;
using Vec3 = glm::vec3;
using Vec4 = glm::vec4;
using Mat4 = glm::mat4;
using DVec3 = glm::dvec3;

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 1.0f / kPi;
constexpr float kInf = std::numeric_limits<float>::infinity();

inline float luminance(const Vec3& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }
inline float maxComponent(const Vec3& v) { return std::max(v.x, std::max(v.y, v.z)); }
inline bool isBlack(const Vec3& c) { return c.x <= 0.f && c.y <= 0.f && c.z <= 0.f; }
inline bool isFinite(const Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
inline bool isFinite(const Vec4& v) { return isFinite(Vec3(v)) && std::isfinite(v.w); }
inline float sqr(float x) { return x * x; }
// int(std::floor(x)) for finite x inside int's range, without the library call or rounding
// mode change that floor costs where SSE4.1 is not assumed.
inline int floorToInt(float x) {
    const int i = int(x);
    return i - (x < float(i));
}
inline int ceilToInt(float x) { return -floorToInt(-x); }
// Bits of x spread to every third position (x < 2^10): one axis of a 30-bit Morton code.
inline uint32_t spreadBits(uint32_t x) {
    x = (x | x << 16) & 0x030000ffu;
    x = (x | x << 8) & 0x0300f00fu;
    x = (x | x << 4) & 0x030c30c3u;
    x = (x | x << 2) & 0x09249249u;
    return x;
}
// The number of set bits, in a few instructions where the popcnt instruction is not assumed
// (the builtin is then a library call).
inline int bitCount(uint64_t v) {
    v -= (v >> 1) & 0x5555555555555555ull;
    v = (v & 0x3333333333333333ull) + ((v >> 2) & 0x3333333333333333ull);
    v = (v + (v >> 4)) & 0x0f0f0f0f0f0f0f0full;
    return int((v * 0x0101010101010101ull) >> 56);
}

struct Bounds3 {
    Vec3 lo{kInf};
    Vec3 hi{-kInf};

    void extend(const Vec3& p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
    void extend(const Bounds3& b) { lo = glm::min(lo, b.lo); hi = glm::max(hi, b.hi); }
    bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
    Vec3 extent() const { return empty() ? Vec3(0.f) : hi - lo; }
    Vec3 center() const { return 0.5f * (lo + hi); }
    float diagonal() const { return glm::length(extent()); }
};

// A cylinder o + tω (radius r) against an axis-aligned box, one face at a time: with
// r = r_a = radius·sqrt(1 − ω_a²), the disc perpendicular to ω at t has half-extent r_a on
// axis a, and the face keeps the part of [t0, t1] where that disc's box reaches past it.
// Applying all six faces leaves the t-range whose disc boxes touch the box (empty: t0 > t1).
inline void clipLowerFace(float o, float w, float r, float lo, float& t0, float& t1) {
    float d = (lo - r) - o;
    if (w > 0.f) t0 = std::max(t0, d / w);
    else if (w < 0.f) t1 = std::min(t1, d / w);
    else if (d > 0.f) t0 = kInf;
}
inline void clipUpperFace(float o, float w, float r, float hi, float& t0, float& t1) {
    float d = (hi + r) - o;
    if (w > 0.f) t1 = std::min(t1, d / w);
    else if (w < 0.f) t0 = std::max(t0, d / w);
    else if (d < 0.f) t0 = kInf;
}

// The half-extents r_a = radius·sqrt(1 − ω_a²) of the disc perpendicular to the unit ω.
inline void discHalfExtents(const Vec3& w, float radius, float r[3]) {
    for (int a = 0; a < 3; ++a) r[a] = radius * std::sqrt(std::max(0.f, 1.f - w[a] * w[a]));
}
// All six faces of the box [lo, hi], axis by axis: [t0, t1] becomes the t-range whose disc
// boxes (half-extents r) touch the box.
inline void clipToBox(const Vec3& o, const Vec3& w, const float r[3], const Vec3& lo, const Vec3& hi, float& t0,
                      float& t1) {
    for (int a = 0; a < 3; ++a) {
        clipLowerFace(o[a], w[a], r[a], lo[a], t0, t1);
        clipUpperFace(o[a], w[a], r[a], hi[a], t0, t1);
    }
}

// Right-handed orthonormal frame around a unit normal (Duff et al.'s branchless basis).
struct Frame {
    Vec3 s, t, n;

    Frame() : s(1, 0, 0), t(0, 1, 0), n(0, 0, 1) {}
    explicit Frame(const Vec3& normal) : n(normal) {
        float sign = std::copysign(1.0f, n.z);
        float a = -1.0f / (sign + n.z);
        float b = n.x * n.y * a;
        s = Vec3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
        t = Vec3(b, sign + n.y * n.y * a, -n.y);
    }
    Vec3 toLocal(const Vec3& v) const { return {glm::dot(v, s), glm::dot(v, t), glm::dot(v, n)}; }
    Vec3 toWorld(const Vec3& v) const { return v.x * s + v.y * t + v.z * n; }
};

}  // namespace rs
