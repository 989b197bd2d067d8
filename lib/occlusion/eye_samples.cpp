// Eye samples and their encodings (eye_samples.h).
#include "occlusion/eye_samples.h"

#include <algorithm>

#include "core/parallel.h"
#include "scene/bsdf.h"

namespace rs {

namespace {

Vec2 octWrap(Vec2 v) {
    return (Vec2(1.f) - glm::abs(Vec2(v.y, v.x))) * Vec2(v.x >= 0.f ? 1.f : -1.f, v.y >= 0.f ? 1.f : -1.f);
}

uint32_t quantize(float x) { return uint32_t(std::lround(std::clamp(x * 0.5f + 0.5f, 0.f, 1.f) * 65535.f)); }

}  // namespace

// The octahedral map's point p ∈ [−1, 1]² of a unit vector, and back.
static Vec2 octahedral(const Vec3& n) {
    Vec3 a = glm::abs(n);
    float l1 = a.x + a.y + a.z;
    Vec2 p = l1 > 0.f ? Vec2(n.x, n.y) / l1 : Vec2(0.f);
    return n.z < 0.f ? octWrap(p) : p;
}

static Vec3 fromOctahedral(Vec2 p) { return octahedralToUnit(p.x, p.y); }

uint32_t encodeUnit(const Vec3& n) {
    const Vec2 p = octahedral(n);
    return quantize(p.x) | (quantize(p.y) << 16);
}

Vec3 decodeUnit(uint32_t e) {
    return fromOctahedral(Vec2(float(e & 0xffffu) / 65535.f * 2.f - 1.f, float(e >> 16) / 65535.f * 2.f - 1.f));
}

// 255 levels a coordinate, so that 0 (and with it every axis-aligned normal) is exact.
uint16_t encodeUnit16(const Vec3& n) {
    const Vec2 p = octahedral(n);
    auto q = [](float x) { return uint32_t(std::lround(std::clamp(x * 0.5f + 0.5f, 0.f, 1.f) * 254.f)); };
    return uint16_t(q(p.x) | q(p.y) << 8);
}


uint32_t encodeRgb9e5(const Vec3& c) {
    const float r = std::clamp(c.x, 0.f, kMaxRgb9e5), g = std::clamp(c.y, 0.f, kMaxRgb9e5),
                b = std::clamp(c.z, 0.f, kMaxRgb9e5);
    const float m = std::max(r, std::max(g, b));  // NaN channels clamp to 0 above
    if (!(m > 0.f)) return 0;
    int exponent = std::max(-16, int(std::floor(std::log2(m)))) + 16;  // biased, m < 2^(exponent − 15)
    float scale = std::ldexp(1.f, 24 - exponent);
    if (std::lround(m * scale) > 511) ++exponent, scale *= 0.5f;
    exponent = std::min(exponent, 30);
    auto q = [&](float v) { return uint32_t(std::min(511l, std::lround(v * scale))); };
    return q(r) | q(g) << 9 | q(b) << 18 | uint32_t(exponent) << 27;
}

Vec3 EyeSamples::weightedF(size_t i, const Vec3& wi, float cosI, float diffuseShadowing) const {
    const uint32_t r = bsdf[i];
    return isGlossy(r) ? glossyF(r, wi, cosI, diffuseShadowing) : decodeRgb9e5(r) * diffuseShadowing;
}

Vec3 EyeSamples::glossyF(uint32_t r, const Vec3& wi, float cosI, float diffuseShadowing) const {
    const GlossyLobe& lobe = lobes[lobeIndex(r)];
    Vec3 f = decodeRgb9e5(lobe.diffuse) * diffuseShadowing;
    const Vec3 wo = decodeUnit(lobe.toViewer), m = decodeUnit(lobe.normal);
    const float cosO = glm::dot(m, wo), cosIm = glm::dot(m, wi);
    if (cosO <= 0.f || cosIm <= 0.f) return f;
    const Vec3 h = glm::normalize(wo + wi);
    const GgxReflection g = ggxReflection(cosO, cosIm, glm::dot(m, h), glm::dot(wo, h), lobe.alpha);
    const Vec3 specular = decodeRgb9e5(lobe.specular), weight = decodeRgb9e5(lobe.weight);
    return f + (specular + (weight - specular) * g.m5) * (g.dg * (cosIm / cosI));
}

void EyeSamples::add(const Vec3& p, const Vec3& ns, const Vec3& ng, bool bent, uint32_t px, const Vec3& diffuse,
                     const GlossyLobe* lobe) {
    position.push_back(p);
    normal.push_back(encodeUnit16(ns));
    geomNormal.push_back(encodeUnit16(ng));
    bumped.push_back(bent ? 1 : 0);
    pixel.push_back(px);
    if (!lobe) {
        bsdf.push_back(encodeRgb9e5(diffuse));
        return;
    }
    bsdf.push_back(kLobeFlag | uint32_t(lobes.size()));
    lobes.push_back(*lobe);
    lobes.back().diffuse = encodeRgb9e5(diffuse);
}

size_t EyeSamples::bytes() const {
    return size() * kBytesPerSample + lobes.size() * sizeof(GlossyLobe);
}

void EyeSamples::reserve(size_t n) {
    position.reserve(n);
    normal.reserve(n);
    geomNormal.reserve(n);
    bumped.reserve(n);
    pixel.reserve(n);
    bsdf.reserve(n);
}

void EyeSamples::append(const EyeSamples& o) {
    const uint32_t lobeBase = uint32_t(lobes.size());
    position.insert(position.end(), o.position.begin(), o.position.end());
    normal.insert(normal.end(), o.normal.begin(), o.normal.end());
    geomNormal.insert(geomNormal.end(), o.geomNormal.begin(), o.geomNormal.end());
    bumped.insert(bumped.end(), o.bumped.begin(), o.bumped.end());
    pixel.insert(pixel.end(), o.pixel.begin(), o.pixel.end());
    for (uint32_t r : o.bsdf) bsdf.push_back(isGlossy(r) ? kLobeFlag | (lobeIndex(r) + lobeBase) : r);
    lobes.insert(lobes.end(), o.lobes.begin(), o.lobes.end());
}

template <class T>
static void permuteArray(std::vector<T>& v, const std::vector<uint32_t>& order, ThreadPool& pool) {
    std::vector<T> out(order.size());
    pool.parallelFor(int64_t(order.size()), 1 << 16, [&](int64_t b, int64_t e, int) {
        for (int64_t i = b; i < e; ++i) out[size_t(i)] = v[order[size_t(i)]];
    });
    v.swap(out);
}

void EyeSamples::permute(const std::vector<uint32_t>& order, ThreadPool& pool) {
    permuteArray(position, order, pool);
    permuteArray(normal, order, pool);
    permuteArray(geomNormal, order, pool);
    permuteArray(bumped, order, pool);
    permuteArray(pixel, order, pool);
    permuteArray(bsdf, order, pool);
}

}  // namespace rs

