// Light sampling shared by the path tracer (next-event estimation, MIS) and the photon
// tracer (emission): every emissive triangle and punctual light, and the environment, chosen
// by power.
#pragma once

#include <vector>

#include "scene/accel.h"
#include "scene/environment.h"

namespace rs {

struct LightSample {
    Vec3 wi{0.f};        // unit, from the shading point towards the light
    float dist = 0.f;    // to the light point (kInf for directional)
    Vec3 radiance{0.f};  // Li at the shading point, before the cosine and visibility
    float pdf = 0.f;     // solid-angle pdf for area lights and the environment, choice probability for delta lights
    bool delta = false;
};

struct EmissionSample {
    Vec3 origin{0.f}, dir{0.f};  // dir unit
    Vec3 flux{0.f};              // Le·cos / (pdfPos·pdfDir·pChoice): the photon's flux
    float pdfDir = 0.f;          // solid-angle pdf of dir at origin (0: delta / collimated)
    float pdfChoicePos = 0.f;    // pChoice · pdf of the position (per area; 1 for a point)
    float choiceProb = 0.f;      // probability of having chosen this light
    Vec3 normal{0.f};            // the emitting surface's normal (area lights), else 0
    bool collimated = false;     // directional light or environment: density is per perpendicular area
};

class LightSampler {
public:
    // `environment`: null or black for none; it must outlive the sampler.
    explicit LightSampler(const Scene& scene, const Environment* environment = nullptr);

    bool empty() const { return cdf_.empty(); }
    // The environment, or null: what a ray that leaves the scene sees.
    const Environment* environment() const { return environment_; }
    // Solid-angle pdf that sampleLi picks direction `dir` of the environment.
    float pdfEnvironment(const Vec3& dir) const;
    // Next-event estimation towards one light chosen by power.
    LightSample sampleLi(const Vec3& p, float uChoice, Vec2 u) const;
    // Where u lies inside the interval of the light it picks, in [0, 1): one number both chooses
    // the light and places the point on it, so that stratified numbers stay stratified on
    // each light.
    float withinChoice(float u) const;
    // Solid-angle pdf that sampleLi from `p` picks point `pl` on emissive triangle `tri`.
    float pdfLi(const Vec3& p, uint32_t tri, const Vec3& pl) const;
    // A photon leaving a light: 1 number picks the light, 2 the position, 2 the direction.
    // With light portals (Scene::portals), photons of directional lights and of the environment
    // cross a portal: a point on them chosen by area projected across the photon's direction.
    EmissionSample sampleEmission(float uChoice, Vec2 uPos, Vec2 uDir) const;
    // Which of those numbers it reads: the choice only where there are several lights, the
    // position but for point and spot lights alone. A photon tracer need not draw the others.
    bool emissionChooses() const { return cdf_.size() > 1; }
    bool emissionPlaces() const { return emissionPlaces_; }
    bool hasPortals() const { return !portals_.empty(); }
    // Whether direct light at `p` on a surface (`glossy`: with a GGX lobe) also takes BSDF-sampled
    // rays, MIS-weighted against the light samples (docs/design.md §4). Not where no ray can meet
    // a light (punctual lights alone), nor on a Lambert surface outside every emitter
    // triangle's sphere (its centroid, kNearEmitter times its farthest vertex): there the light
    // samples take the whole weight. On the staircase (its 2 × 2 m ceiling lamp) and the Cornell
    // box the direct layer's rel. MSE was the same to 1 % with and without them (2.897e-4 against
    // 2.889e-4; 1.014e-4 against 1.013e-4), and the staircase's eye pass took 3.2 s, not 4.1.
    // Inside such a sphere, under an environment, with more emitters than kMaxNearTests, and on
    // glossy surfaces, they are taken.
    bool wantsBsdfSamples(const Vec3& p, bool glossy) const;
    static constexpr float kNearEmitter = 1.f;
    static constexpr size_t kMaxNearTests = 64;

private:
    enum class Kind : uint8_t { Area, Punctual, Environment };
    struct Entry {
        Kind kind = Kind::Area;
        uint32_t index = 0;  // triangle or punctual light
        float power = 0.f;
        // A textured emitter's texel grid (cellCdf_[gridFirst, gridFirst + gridSide²)); side 0:
        // points uniform over the triangle.
        uint32_t gridSide = 0, gridFirst = 0;
        // A point light outside the scene's bounds along an axis sends photons only towards them
        // along it: per axis, 0 free, +1 or −1 the sign the direction's component must have.
        int8_t toward[3] = {0, 0, 0};
    };
    // A textured emitter's points follow its texels: a grid of cells over the unit square that
    // sampleUniformTriangle maps onto the triangle (preserving area), each cell chosen by the
    // luminance of its emission, floored at kGridFloor of the mean cell so that no emitting
    // point is left out (the estimate stays unbiased), the point uniform within its cell.
    static constexpr int kMaxGridSide = 32;
    static constexpr float kGridFloor = 0.05f;
    void buildTexelGrid(Entry& e);
    // Barycentrics of a point on entry e's triangle, and its density relative to uniform.
    Vec2 sampleOnEmitter(const Entry& e, Vec2 u, float& density) const;
    float densityOnEmitter(const Entry& e, Vec2 b) const;
    float probability(size_t entry) const { return cdf_[entry] - (entry ? cdf_[entry - 1] : 0.f); }
    size_t choose(float u, float& prob) const;
    // Σ A·|n·d| over the portal triangles: their area seen along d.
    float portalArea(const Vec3& d) const;
    // A photon along d through a point of the portals chosen by projected area (u), starting
    // where the line leaves the scene's bounding sphere backwards; false when no portal faces d.
    bool throughPortal(const Vec3& d, Vec2 u, EmissionSample& s, float& area) const;

    const Scene& scene_;
    std::vector<Entry> entries_;
    std::vector<float> cdf_;              // normalised, cdf_.back() == 1
    std::vector<int32_t> entryOfTriangle_;  // -1 for non-emissive triangles
    std::vector<float> cellCdf_;           // the texel grids, each normalised
    const Environment* environment_ = nullptr;
    struct PortalTriangle {
        Vec3 v0, v1, v2;
        Vec3 areaNormal;  // area × unit normal
    };
    std::vector<PortalTriangle> portals_;  // those with area
    int32_t environmentEntry_ = -1;
    Vec3 sceneCenter_;
    float sceneRadius_ = 1.f;
    bool onlyPunctual_ = false;
    bool emissionPlaces_ = true;  // sampleEmission reads uPos
    std::vector<glm::vec4> emitterSpheres_;  // each emissive triangle's centroid and kNearEmitter × its reach
};

}  // namespace rs
