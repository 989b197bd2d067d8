// Light sampling shared by the path tracer (next-event estimation, MIS) and the photon
// tracer (emission): every emissive triangle and punctual light, chosen by power.
#pragma once

#include <vector>

#include "scene/accel.h"

namespace rs {

struct LightSample {
    Vec3 wi{0.f};        // unit, from the shading point towards the light
    float dist = 0.f;    // to the light point (kInf for directional)
    Vec3 radiance{0.f};  // Li at the shading point, before the cosine and visibility
    float pdf = 0.f;     // solid-angle pdf for area lights, choice probability for delta lights
    bool delta = false;
};

struct EmissionSample {
    Vec3 origin{0.f}, dir{0.f};  // dir unit
    Vec3 flux{0.f};              // Le·cos / (pdfPos·pdfDir·pChoice): the photon's flux
    float pdfDir = 0.f;          // solid-angle pdf of dir at origin (0: delta / collimated)
    float pdfChoicePos = 0.f;    // pChoice · pdf of the position (per area; 1 for a point)
    float choiceProb = 0.f;      // probability of having chosen this light
    Vec3 normal{0.f};            // the emitting surface's normal (area lights), else 0
    bool collimated = false;     // directional light: density is per perpendicular area
};

class LightSampler {
public:
    explicit LightSampler(const Scene& scene);

    bool empty() const { return cdf_.empty(); }
    // Next-event estimation towards one light chosen by power.
    LightSample sampleLi(const Vec3& p, float uChoice, Vec2 u) const;
    // Where u lies inside the interval of the light it picks, in [0, 1): one number both chooses
    // the light and places the point on it, so that stratified numbers stay stratified on
    // each light.
    float withinChoice(float u) const;
    // Solid-angle pdf that sampleLi from `p` picks point `pl` on emissive triangle `tri`.
    float pdfLi(const Vec3& p, uint32_t tri, const Vec3& pl) const;
    // A photon leaving a light: 1 number picks the light, 2 the position, 2 the direction.
    EmissionSample sampleEmission(float uChoice, Vec2 uPos, Vec2 uDir) const;

private:
    struct Entry {
        bool area = false;
        uint32_t index = 0;  // triangle or punctual light
        float power = 0.f;
    };
    size_t choose(float u, float& prob) const;

    const Scene& scene_;
    std::vector<Entry> entries_;
    std::vector<float> cdf_;              // normalised, cdf_.back() == 1
    std::vector<int32_t> entryOfTriangle_;  // -1 for non-emissive triangles
    Vec3 sceneCenter_;
    float sceneRadius_ = 1.f;
};

}  // namespace rs
