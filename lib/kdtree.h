// Occlusion tree (DESIGN §7, paper §5): a kd-tree of 8-byte nodes over the OcclusionGrid
// that merges empty space and indexes the eye samples, built top-down on the CPU.
//
// Takes:   the OcclusionGrid and the EyeSamples (world positions → voxel space with
//          grid.geometry.voxelFromWorld).
// Returns: the OcclusionTree; the eye samples are reordered in place so that each Visible
//          node's samples are contiguous. Samples outside the grid (or non-finite) are not
//          an error: they are moved to the end, [tree.sampleCount, samples.size()), belong to
//          no node and receive no photon energy; stats.samplesOutside counts them so the
//          caller can warn (the grid is the scene's bounds padded by a voxel, so with a
//          matching grid there are none).
// Space:   everything in voxel space (one unit a voxel, origin at the grid's min corner).
//
// Build: a temporary 3D summed-area table of "interesting" voxels (occupied, or holding an
// eye sample) gives the count of any box in O(1). A node's box is split on its longest axis
// (ties: lowest axis) at the spatial median voxel boundary, or, when one side of the median
// holds nothing interesting, at the boundary of the closest interesting voxel slab, which
// cuts the empty space off into an Empty node. A box with nothing interesting is Empty. A
// single voxel is an Occlusion leaf (occupied) or an Empty leaf, with a Visible node right
// above it when the voxel holds eye samples. A Split whose two children are equal
// Occlusion leaves collapses into one Occlusion node (bottom-up: a uniform, sample-free,
// fully occupied sub-tree becomes one node). Single-threaded and deterministic; the SAT is
// built on the pool.
//
// Traversal of a cylinder: kdtree_traverse.h.
//
// Layout: depth first; a Split's lower child follows it, its upper child's index is stored;
// a Visible node's child follows it. The root is node 0.
#pragma once

#include <cstdint>
#include <vector>

#include "eye.h"
#include "math.h"
#include "occlusion_grid.h"
#include "parallel.h"

namespace rs {

constexpr int kMaxTreeDim = 4096;  // split planes are stored in 13 bits

enum class NodeType : uint32_t { Empty = 0, Split = 1, Occlusion = 2, Visible = 3 };

// One 64-bit word:
//   bits 0-1  type
//   Split:     2-3 axis, 4-16 plane (voxel boundary 0…4096), 32-63 index of the upper child
//   Visible:   2-31 sample count, 32-63 first sample index
//   Occlusion: 2-3 dominant axis, 4 ambiguous, 5-34 the six side counts (5 bits each, Side
//              order, 0…16), 35-58 quantized mean normal (3 × int8, ×127, paper Fig. 3)
struct Node {
    uint64_t bits = 0;

    NodeType type() const { return NodeType(bits & 3u); }

    int axis() const { return int(bits >> 2) & 3; }
    int plane() const { return int(bits >> 4) & 0x1fff; }
    uint32_t upperChild() const { return uint32_t(bits >> 32); }

    uint32_t sampleCount() const { return uint32_t(bits >> 2) & 0x3fffffffu; }
    uint32_t firstSample() const { return uint32_t(bits >> 32); }

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
    static Node visible(uint32_t first, uint32_t count) {
        return Node{uint64_t(NodeType::Visible) | uint64_t(count) << 2 | uint64_t(first) << 32};
    }
    static Node occlusion(const uint8_t counts[kSideCount]);
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
    std::vector<Node> nodes;   // root at 0
    uint32_t sampleCount = 0;  // eye samples [0, sampleCount) are in Visible nodes

    size_t bytes() const { return nodes.size() * sizeof(Node); }
};

struct OcclusionTreeStats {
    size_t nodes = 0, empty = 0, split = 0, occlusion = 0, visible = 0;
    size_t collapsedVoxels = 0;  // voxels inside multi-voxel Occlusion nodes
    size_t bytes = 0;
    size_t samplesOutside = 0;
    int depth = 0;
    double satSeconds = 0, buildSeconds = 0, sortSeconds = 0, totalSeconds = 0;
};

OcclusionTree buildOcclusionTree(const OcclusionGrid& grid, EyeSamples& samples, ThreadPool& pool,
                                 OcclusionTreeStats* stats = nullptr);

}  // namespace rs
