// Eye samples (docs/design.md §4, §6): where photon energy lands. The eye pass (splat/eye.h)
// stores them; the occlusion tree is built over them and reorders them; the splat reads them.
// Compact: positions, 16-bit octahedral normals and an RGB9E5 BSDF word a sample.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/math.h"

namespace rs {

class ThreadPool;

// Octahedral encoding of a unit vector in 32 bits (16 bits a coordinate): ~0.005° error;
// in 16 bits (8 bits a coordinate): ~0.5° error.
uint32_t encodeUnit(const Vec3& n);
Vec3 decodeUnit(uint32_t e);
uint16_t encodeUnit16(const Vec3& n);
// The unit vector of the octahedral map's point (x, y) ∈ [−1, 1]².
inline Vec3 octahedralToUnit(float x, float y) {
    Vec3 n(x, y, 1.f - std::abs(x) - std::abs(y));
    float t = std::max(-n.z, 0.f);
    n.x += n.x >= 0.f ? -t : t;
    n.y += n.y >= 0.f ? -t : t;
    return glm::normalize(n);
}
inline Vec3 decodeUnit16(uint16_t e) {  // inline: the splat decodes two a contribution
    return octahedralToUnit(float(e & 0xffu) * (2.f / 254.f) - 1.f, float(e >> 8) * (2.f / 254.f) - 1.f);
}

// A non-negative RGB in 32 bits with a shared exponent (9-bit mantissas, 5-bit exponent):
// relative error under 2^-9 of the largest channel, values up to kMaxRgb9e5 (larger ones are
// clamped). Exponent 31 is not a colour: EyeSamples marks its glossy samples with it.
constexpr float kMaxRgb9e5 = 32704.f;
uint32_t encodeRgb9e5(const Vec3& c);
inline Vec3 decodeRgb9e5(uint32_t e) {
    // 2^(exponent − bias 15 − 9 mantissa bits), built as a float's bits (exponent − 24 ≥ −24).
    const uint32_t bits = uint32_t(int(e >> 27) - 24 + 127) << 23;
    float scale;
    std::memcpy(&scale, &bits, sizeof scale);
    return Vec3(float(e & 511u), float(e >> 9 & 511u), float(e >> 18 & 511u)) * scale;
}

// What a glossy eye sample needs to evaluate its BSDF for any light direction (bsdf.h's
// ggxReflection): colours already multiplied by the sample's weight.
struct GlossyLobe {
    uint32_t diffuse;   // RGB9E5: weight × the diffuse lobe's f (albedo·(1 − metallic)/π)
    uint32_t specular;  // RGB9E5: weight × Fresnel at normal incidence f0
    uint32_t weight;    // RGB9E5: weight (Schlick: weight·f0 + (weight − weight·f0)·(1 − cos)^5)
    uint32_t toViewer;  // encodeUnit
    uint32_t normal;    // encodeUnit: the GGX lobe's normal seen from the viewer (Bsdf::specularNormal)
    float alpha;        // GGX α
};

// Eye samples, structure of arrays, 25 bytes a sample and a GlossyLobe more for each glossy
// one. Sample i: world position, shading normal (the one the BSDF frames, on the viewer's
// side), geometric normal (turned to the viewer's side), whether a normal map bent the shading
// normal (Bsdf::bumped: its diffuse lobe takes bumpShadowing), pixel index (y·width + x) and its
// BSDF (`bsdf`): for a Lambert sample weight × f as RGB9E5, for a glossy one exponent 31 and
// the index of its lobe in `lobes`. The weight is 1/S × the throughput of the specular chain
// that led here. `lobes` is indexed, not reordered by permute.
struct EyeSamples {
    std::vector<Vec3> position;
    std::vector<uint16_t> normal;      // encodeUnit16
    std::vector<uint16_t> geomNormal;  // encodeUnit16
    std::vector<uint8_t> bumped;       // 1: a normal map bent `normal`
    std::vector<uint32_t> pixel;
    std::vector<uint32_t> bsdf;
    std::vector<GlossyLobe> lobes;

    static constexpr uint32_t kLobeFlag = 31u << 27;
    static bool isGlossy(uint32_t bsdf) { return (bsdf >> 27) == 31u; }
    static uint32_t lobeIndex(uint32_t bsdf) { return bsdf & ((1u << 27) - 1u); }

    // weight × f_r(wi, to the viewer) of sample i for light leaving along the unit direction
    // wi, given cosI = n·wi > 0 for its decoded shading normal n and the diffuse lobe's
    // bumpShadowing (bsdf.h's eval, from the stored parts).
    Vec3 weightedF(size_t i, const Vec3& wi, float cosI, float diffuseShadowing) const;
    // weightedF of a glossy sample, given its `bsdf` word: its GGX term scaled by the cosine
    // to the lobe's own normal over cosI, as Bsdf::eval does.
    Vec3 glossyF(uint32_t bsdf, const Vec3& wi, float cosI, float diffuseShadowing) const;

    // diffuse: weight × the Lambert f; lobe: the glossy part, if any (its diffuse is set here).
    void add(const Vec3& p, const Vec3& shadingNormal, const Vec3& geomNormal, bool bumped, uint32_t pixel,
             const Vec3& diffuse, const GlossyLobe* lobe = nullptr);
    // Bytes a sample, and a glossy one's lobe more.
    static constexpr size_t kBytesPerSample = sizeof(Vec3) + 2 * sizeof(uint16_t) + 1 + 2 * sizeof(uint32_t);
    size_t size() const { return position.size(); }
    size_t bytes() const;
    void reserve(size_t n);
    void append(const EyeSamples& other);
    // Reorders the per-sample arrays: new sample i is old sample order[i].
    void permute(const std::vector<uint32_t>& order, ThreadPool& pool);
};

}  // namespace rs
