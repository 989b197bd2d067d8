// Indirect light at sparse receivers (docs/design.md §8, "Sparse receivers"). An indirect
// photon's kernel is wide (the 6-voxel floor) and the light it leaves is smooth across it, so
// splatting it on every eye sample, four a pixel each with its own visibility ray, pays for a
// resolution the estimate does not have. Instead a pass's eye samples are thinned to
// *receivers* about `spacing` apart on each surface; indirect photons are splatted on them
// alone, as irradiance (their w·f_r is 1), and every eye sample takes the weighted mean of the
// receivers near it on its own surface, times its own w·f_r (gatherIrradiance). Glossy samples,
// whose f_r depends on where the light comes from, receive for themselves.
//
// A receiver stands for a sample when it lies within `spacing` of it, their shading normals
// are within 25.8° and their geometric normals on one side, and each lies within a tenth of the
// spacing of the other's tangent plane: a thin part, the far side of a corner or a surface
// just behind another never borrow each other's light. The receivers are chosen per screen
// tile of 16×16 pixels and per world cell of twice the spacing, greedily in an order shuffled by
// a hash of the sample (dart throwing: scan order would put them along surfaces' edges): a
// sample no receiver of its tile and cell stands for becomes one. So every sample has one
// within `spacing`, a thin part or a surface seen at a grazing angle keeps as many receivers
// as it needs, and a wall far from the camera few. With the same photons, the staircase
// interior's indirect light at spacing ¼ is 0.997 of the full-density splat's (½: 0.997, 1: 0.994).
// The spacing is ½ of the smallest radius in a pass of one photon round, ½/√R in a pass of R
// (splat_pass.cpp): against path-traced references every scene in data/ has the same or less
// error than at ¼ in the same passes (the receivers' smoothing takes out some of the photons'
// noise) and renders in 5–18 % less time; at ¾ and 1 the point lights' error grows again, and
// with six rounds ½ has 8 % more error than ¼ (docs/performance.md).
//
// Takes:   the eye pass's samples in pixel order (before the tree reorders them), the spacing.
// Returns: the receivers as EyeSamples whose `pixel` is their slot in a film of slots() values,
//          and the cells that gatherIrradiance looks them up in.
// World space, metres. Deterministic: nothing depends on threads.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/math.h"
#include "occlusion/eye_samples.h"

namespace rs {

class ThreadPool;

struct IrradianceSettings {
    // The receivers' spacing in indirect kernel radii: the smallest radius a pass's indirect
    // photons can have (the floor, after the pass's shrinkage and the kernel scale) times this.
    // 0: every eye sample receives for itself (and for --direct photons and splat-novis).
    float spacing = 0.5f;
    static constexpr float kMinNormalCos = 0.9f;     // shading normals within 25.8°
    static constexpr float kMaxPlaneOffset = 0.1f;   // off each other's tangent planes, in spacings
    static constexpr int kTile = 16;                 // pixels: the screen tiles receivers are chosen in
};

struct IrradianceReceivers {
    float spacing = 0.f;  // metres
    EyeSamples samples;   // the receivers, for the tree and the splat: `pixel` is the slot
    // Slots [0, irradianceSlots) gather irradiance (bsdf word: white 1); the others are glossy
    // eye samples, each receiving its own light for pixel glossyPixel[slot − irradianceSlots].
    uint32_t irradianceSlots = 0;
    std::vector<uint32_t> glossyPixel;
    // The irradiance receivers by slot, as gatherIrradiance reads them.
    std::vector<Vec3> position;
    std::vector<uint16_t> normal, geomNormal;
    // Cells of 2 × spacing: an open-addressing table of cell keys, each with its run of slots
    // (the irradiance slots are in the order of their cells).
    std::vector<uint64_t> tableKey;
    std::vector<uint32_t> tableBegin, tableEnd;

    size_t slots() const { return samples.size(); }
    size_t bytes() const;
};

// The receivers of `samples` (in pixel order) of a width × height image, `spacing` metres apart.
IrradianceReceivers chooseReceivers(const EyeSamples& samples, int width, int height, float spacing, ThreadPool& pool);

// Adds every eye sample's indirect light to `pixels` (pixel × RGB, fixed point at `fixedScale`):
// a glossy sample's slot as it received it, a Lambert sample's w·f_r times the weighted mean
// of its receivers' irradiance, from `slots` (slot × RGB, fixed point). `samples` may be in any
// order (the tree's): each sample's light is rounded on its own and added as an integer.
// Several sums of slots at once (one search for their receivers), each into its own pixels:
// pixels[k] gets what a gather of slots[k] alone gives it, to the bit.
void gatherIrradiance(const IrradianceReceivers& receivers, const EyeSamples& samples,
                      const std::vector<const std::vector<int64_t>*>& slots, double fixedScale,
                      const std::vector<std::vector<int64_t>*>& pixels, ThreadPool& pool);
// The seconds gatherIrradiance takes over `samples`: one chunk of samples in sixteen searched
// for their receivers and weighed (no sums read or written) and timed. A time limit's splat stops that long
// before the deadline, so that its gather ends by it.
double gatherSeconds(const IrradianceReceivers& receivers, const EyeSamples& samples, ThreadPool& pool);
inline void gatherIrradiance(const IrradianceReceivers& receivers, const EyeSamples& samples, const std::vector<int64_t>& slots,
                             double fixedScale, std::vector<int64_t>& pixels, ThreadPool& pool) {
    gatherIrradiance(receivers, samples, {&slots}, fixedScale, {&pixels}, pool);
}

// A receiver's weight for an eye sample (0: it does not stand for it): (1 − d²/s²)² within the
// spacing s on the same surface (IrradianceSettings). The choice and the gather ask the same.
// The receiver's normals come encoded (EyeSamples): most receivers asked lie past the spacing,
// and are refused before their normals are decoded.
// Inline: the gather asks it for every receiver in the eight cells around each eye sample.
inline float receiverWeight(const Vec3& sample, const Vec3& sampleNormal, const Vec3& sampleGeomNormal, const Vec3& receiver,
                            uint16_t receiverNormal16, uint16_t receiverGeomNormal16, float spacing) {
    const Vec3 d = receiver - sample;
    const float s2 = spacing * spacing, d2 = glm::dot(d, d);
    if (!(d2 < s2)) return 0.f;
    const Vec3 receiverNormal = decodeUnit16(receiverNormal16), receiverGeomNormal = decodeUnit16(receiverGeomNormal16);
    if (glm::dot(sampleNormal, receiverNormal) < IrradianceSettings::kMinNormalCos) return 0.f;
    if (!(glm::dot(sampleGeomNormal, receiverGeomNormal) > 0.f)) return 0.f;
    const float plane = IrradianceSettings::kMaxPlaneOffset * spacing;
    if (std::abs(glm::dot(d, sampleGeomNormal)) > plane || std::abs(glm::dot(d, receiverGeomNormal)) > plane) return 0.f;
    const float x = 1.f - d2 / s2;
    return x * x;
}

}  // namespace rs
