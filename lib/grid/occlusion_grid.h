// OcclusionGrid: the voxelized scene (docs/design.md §5, paper §4). Cubic voxels over the scene's
// bounds padded by one voxel; each voxel stores six occlusion counts, one per side: for
// axis a ∈ {x, y, z} and sign s ∈ {+, −}, how many of the 4×4 sub-samples of the voxel's
// projection along a are covered by surfaces whose normal has sign s along a (0…16; the
// occlusion ratio is count/16). 6 bytes a voxel.
//
// Voxel space ("grid space"): one unit per voxel, origin at the grid's min corner; voxel
// (i, j, k) covers [i, i+1) × [j, j+1) × [k, k+1). worldFromVoxel / voxelFromWorld convert.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/math.h"

namespace rs {

using IVec3 = glm::ivec3;

enum Side : int { kPosX = 0, kNegX, kPosY, kNegY, kPosZ, kNegZ, kSideCount };
constexpr int kSubsamplesPerAxis = 4;                               // 4×4 per voxel face
constexpr int kSubsamples = kSubsamplesPerAxis * kSubsamplesPerAxis;  // a side's count is 0…16
constexpr int kMaxGridResolution = 4096;  // voxels along the longest axis

struct GridGeometry {
    Vec3 origin{0.f};     // world position of the grid's min corner
    float voxelSize = 1;  // world units (m) per voxel
    IVec3 dims{0};

    Vec3 worldFromVoxel(const Vec3& pVoxel) const { return origin + pVoxel * voxelSize; }
    Vec3 voxelFromWorld(const Vec3& pWorld) const { return (pWorld - origin) / voxelSize; }
    size_t voxelCount() const { return size_t(dims.x) * dims.y * dims.z; }
    size_t index(int x, int y, int z) const { return size_t(x) + size_t(dims.x) * (size_t(y) + size_t(dims.y) * z); }
    bool contains(int x, int y, int z) const {
        return x >= 0 && y >= 0 && z >= 0 && x < dims.x && y < dims.y && z < dims.z;
    }
};

// The grid for scene bounds: `resolution` voxels along the longest axis, cubic voxels, the
// bounds padded by one voxel on every side (so dims = ceil(extent/size) + 2 per axis).
GridGeometry gridForBounds(const Bounds3& bounds, int resolution);

struct OcclusionGrid {
    GridGeometry geometry;
    std::vector<uint8_t> counts;  // 6 per voxel, in Side order, voxel-major

    OcclusionGrid() = default;
    explicit OcclusionGrid(const GridGeometry& g) : geometry(g), counts(g.voxelCount() * kSideCount, 0) {}

    const uint8_t* voxel(size_t i) const { return &counts[i * kSideCount]; }
    uint8_t* voxel(size_t i) { return &counts[i * kSideCount]; }
    float ratio(size_t i, Side s) const { return counts[i * kSideCount + s] / float(kSubsamples); }
    bool occupied(size_t i) const {
        const uint8_t* c = voxel(i);
        return (c[0] | c[1] | c[2] | c[3] | c[4] | c[5]) != 0;
    }
    // Paper Fig. 3: n ∝ (c+x − c−x, c+y − c−y, c+z − c−z); zero vector for an empty voxel.
    Vec3 meanNormal(size_t i) const {
        const uint8_t* c = voxel(i);
        return Vec3(float(c[kPosX]) - c[kNegX], float(c[kPosY]) - c[kNegY], float(c[kPosZ]) - c[kNegZ]);
    }
    // Both signs present on one axis: front and back facing surfaces share the voxel.
    bool ambiguous(size_t i) const {
        const uint8_t* c = voxel(i);
        return (c[kPosX] && c[kNegX]) || (c[kPosY] && c[kNegY]) || (c[kPosZ] && c[kNegZ]);
    }
    size_t occupiedCount() const;
};

}  // namespace rs
