// Occlusion tree (docs/design.md §6, paper §5): a kd-tree of 8-byte nodes over the
// OcclusionGrid that merges empty space and indexes the eye samples, built top-down on the CPU.
//
// Takes:   the OcclusionGrid and the EyeSamples (world positions → voxel space with
//          grid.geometry.voxelFromWorld).
// Returns: the OcclusionTree; the eye samples are reordered in place so that each brick's
//          samples are contiguous. Samples outside the grid (or non-finite) are not an error:
//          they are moved to the end, [tree.sampleCount, samples.size()), belong to no brick
//          and receive no photon energy; stats.samplesOutside counts them so the caller can
//          warn (the grid is the scene's bounds padded by a voxel, so with a matching grid
//          there are none).
// Space:   everything in voxel space (one unit a voxel, origin at the grid's min corner).
//
// Leaves are *bricks* of 4×4×4 voxels aligned to the grid (the last ones along an axis may be
// cut by the grid): a Brick node holds the index of its payload — a 64-bit occupancy mask, the
// occlusion counts of its occupied voxels in mask order, and its range of eye samples — so a
// cylinder meets one node where it met up to 64 voxel leaves and their Visible nodes, and walks
// the occupied voxels and samples inside with bit operations over contiguous arrays.
//
// Build: a temporary 3D summed-area table over the bricks (a brick is "interesting" when it
// holds an occupied voxel or an eye sample) gives the count of any box of bricks in O(1). A
// box is split on its longest axis (ties: lowest axis) at the spatial median brick boundary,
// or, when one side of the median holds nothing interesting, at the boundary of the closest
// interesting slab, which cuts the empty space off into an Empty node (paper §5). A box with
// nothing interesting is Empty. A single brick is a Brick leaf, or an Occlusion leaf when all
// its voxels are occupied with the same counts and it holds no samples (uniform occlusion); a
// Split whose two children are equal Occlusion leaves collapses into one (bottom-up: a uniform,
// sample-free, fully occupied sub-tree becomes one node). Single-threaded and deterministic;
// the grid scan is done on the pool.
//
// Traversal of a cylinder: kdtree_traverse.h.
//
// Layout: depth first; a Split's lower child follows it, its upper child's index is stored.
// The root is node 0.
#pragma once

#include <cstdint>
#include <vector>

#include "occlusion/eye_samples.h"
#include "core/math.h"
#include "grid/occlusion_grid.h"
#include "core/parallel.h"
#include "core/stats.h"

namespace rs {

constexpr int kMaxTreeDim = kMaxGridResolution;
static_assert(kMaxTreeDim < (1 << 13), "split planes are stored in 13 bits");
constexpr int kBrickShift = 2;     // bricks of 4×4×4 voxels
constexpr int kBrickSize = 1 << kBrickShift;

enum class NodeType : uint32_t { Empty = 0, Split = 1, Occlusion = 2, Brick = 3 };

// The occlusion of one voxel in 32 bits: bits 0-29 the six side counts (5 bits each, Side
// order, 0…16), 30-31 the dominant axis (largest c₊ + c₋, ties: lowest; paper §5.3).
struct VoxelOcclusion {
    uint32_t bits = 0;

    int count(int side) const { return int(bits >> (5 * side)) & 31; }
    int dominantAxis() const { return int(bits >> 30); }
    bool ambiguous() const {
        return (count(0) && count(1)) || (count(2) && count(3)) || (count(4) && count(5));
    }
    static VoxelOcclusion of(const uint8_t counts[6]);
};

// A brick's payload. Voxel (x, y, z) of the brick (0…3 each, from the brick's min corner) is
// bit x + 4y + 16z of `occupied`; the occupied voxels' occlusion is stored from `firstVoxel` on,
// in bit order (`sides` marks them by side); the brick's eye samples are [firstSample, firstSample + sampleCount), ordered
// by the octant of the brick (2×2×2 voxels: x/2 + 2·(y/2) + 4·(z/2)) their voxel is in, so
// that a cylinder can skip the octants it does not reach: octant k's samples start at
// firstSample + octantStart[k − 1] (0 for k = 0) and end where the next one starts
// (sampleCount for k = 7). A brick of more than 65535 samples is not divided (all 0).
struct Brick {
    uint64_t occupied = 0;
    // Per Side: the occupied voxels whose count on that side is not zero. A direction ω sees
    // one side per axis (the one its sign points to), so only the voxels of those three masks
    // can occlude along it.
    uint64_t sides[kSideCount] = {};
    uint32_t firstVoxel = 0;
    uint32_t firstSample = 0;
    uint32_t sampleCount = 0;
    uint16_t octantStart[7] = {};
    // The box its samples' voxel-space positions lie in (lo x, y, z, hi x, y, z), from the
    // brick's min corner in steps of 1/kBoxScale voxel from −kBoxOffset, widened by kBoxPad
    // steps: the traversal skips what it cannot reach without reading the samples.
    uint16_t sampleBox[6] = {};
    uint8_t octantsFilled = 0;  // a divided brick's octants that hold samples: bit k for octant k
    uint8_t pad = 0;            // no indeterminate bytes: trees compare with memcmp

    static constexpr float kBoxScale = 8192.f, kBoxOffset = 0.25f, kBoxPad = 8.f;  // pad: 1e-3 voxel
    void setSampleBox(const Vec3& lo, const Vec3& hi);  // relative to the brick's min corner
    void sampleBounds(const Vec3& corner, Vec3& lo, Vec3& hi) const {
        for (int a = 0; a < 3; ++a) {
            lo[a] = corner[a] + (float(sampleBox[a]) / kBoxScale - kBoxOffset);
            hi[a] = corner[a] + (float(sampleBox[3 + a]) / kBoxScale - kBoxOffset);
        }
    }

    static constexpr uint32_t kMaxDivided = 65535;
    bool divided() const { return sampleCount <= kMaxDivided; }
    uint32_t octantBegin(int k) const { return firstSample + (k == 0 || !divided() ? 0u : octantStart[k - 1]); }
    uint32_t octantEnd(int k) const { return k == 7 || !divided() ? firstSample + sampleCount : octantBegin(k + 1); }
};

// One 64-bit word:
//   bits 0-1  type
//   Split:     2-3 axis, 4-16 plane (voxel boundary 0…4096), 32-63 index of the upper child
//   Brick:     2-31 where its voxels' counts start in OcclusionTree::voxels (kNoVoxelHint from
//              2^30 − 1 on), for the traversal to ask for them when it meets the brick;
//              32-63 index of its payload in OcclusionTree::bricks
//   Occlusion: 2-3 dominant axis, 4 ambiguous, 5-34 the six side counts (5 bits each, Side
//              order, 0…16), 35-58 quantized mean normal (3 × int8, ×127, paper Fig. 3)
struct Node {
    uint64_t bits = 0;

    NodeType type() const { return NodeType(bits & 3u); }

    int axis() const { return int(bits >> 2) & 3; }
    int plane() const { return int(bits >> 4) & 0x1fff; }
    uint32_t upperChild() const { return uint32_t(bits >> 32); }

    uint32_t brick() const { return uint32_t(bits >> 32); }
    static constexpr uint32_t kNoVoxelHint = 0x3fffffffu;
    uint32_t voxelHint() const { return uint32_t(bits >> 2) & kNoVoxelHint; }

    int dominantAxis() const { return int(bits >> 2) & 3; }
    bool ambiguous() const { return (bits >> 4) & 1u; }
    int count(int side) const { return int(bits >> (5 + 5 * side)) & 31; }
    Vec3 normal() const {  // unit length up to quantization; zero when the counts cancel
        auto q = [&](int i) { return float(int8_t(uint8_t(bits >> (35 + 8 * i)))) / 127.f; };
        return Vec3(q(0), q(1), q(2));
    }

    static Node empty() { return Node{}; }
    static Node split(int axis, int plane, uint32_t upper) {
        return Node{uint64_t(NodeType::Split) | uint64_t(axis) << 2 | uint64_t(plane) << 4 | uint64_t(upper) << 32};
    }
    static Node brickLeaf(uint32_t index, uint32_t firstVoxel = kNoVoxelHint) {
        return Node{uint64_t(NodeType::Brick) | uint64_t(std::min(firstVoxel, kNoVoxelHint)) << 2 | uint64_t(index) << 32};
    }
    static Node occlusion(const uint8_t counts[kSideCount]);
    VoxelOcclusion voxel() const {
        return VoxelOcclusion{(uint32_t(bits >> 5) & 0x3fffffffu) | (uint32_t(dominantAxis()) << 30)};
    }
};
static_assert(sizeof(Node) == 8, "paper §5: 8-byte nodes");

// The axis with the largest occlusion c₊ + c₋ (ties: lowest axis): paper §5.3's "dimension
// of highest occlusion", along which ambiguous voxels get their offset.
int dominantAxis(const uint8_t counts[kSideCount]);
inline bool ambiguousCounts(const uint8_t c[kSideCount]) {
    return (c[kPosX] && c[kNegX]) || (c[kPosY] && c[kNegY]) || (c[kPosZ] && c[kNegZ]);
}

struct OcclusionTree {
    GridGeometry geometry;
    std::vector<Node> nodes;             // root at 0
    std::vector<Brick> bricks;           // Brick nodes' payloads
    std::vector<VoxelOcclusion> voxels;  // the bricks' occupied voxels
    uint32_t sampleCount = 0;            // eye samples [0, sampleCount) are in bricks

    size_t bytes() const {
        return nodes.size() * sizeof(Node) + bricks.size() * sizeof(Brick) + voxels.size() * sizeof(VoxelOcclusion);
    }
};

struct OcclusionTreeStats {
    size_t nodes = 0, empty = 0, split = 0, occlusion = 0, bricks = 0, brickVoxels = 0;
    size_t collapsedVoxels = 0;  // voxels inside multi-voxel Occlusion nodes
    size_t bytes = 0;
    size_t samplesOutside = 0;
    int depth = 0;
    double satSeconds = 0, buildSeconds = 0, sortSeconds = 0, totalSeconds = 0;

    void report(Stats& stats) const;  // tree_* counts
};

OcclusionTree buildOcclusionTree(const OcclusionGrid& grid, EyeSamples& samples, ThreadPool& pool,
                                 OcclusionTreeStats* stats = nullptr);

}  // namespace rs
