#include "occlusion/kdtree.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/stats.h"

namespace rs {

int dominantAxis(const uint8_t c[kSideCount]) {
    int best = 0, bestOcc = -1;
    for (int a = 0; a < 3; ++a) {
        int occ = int(c[2 * a]) + int(c[2 * a + 1]);
        if (occ > bestOcc) best = a, bestOcc = occ;
    }
    return best;
}

VoxelOcclusion VoxelOcclusion::of(const uint8_t c[kSideCount]) {
    uint32_t bits = uint32_t(rs::dominantAxis(c)) << 30;
    for (int s = 0; s < kSideCount; ++s) {
        RS_CHECK(c[s] <= kSubsamples);
        bits |= uint32_t(c[s]) << (5 * s);
    }
    return VoxelOcclusion{bits};
}

Node Node::occlusion(const uint8_t c[kSideCount]) {
    uint64_t bits = uint64_t(NodeType::Occlusion) | uint64_t(rs::dominantAxis(c)) << 2 |
                    uint64_t(ambiguousCounts(c) ? 1 : 0) << 4;
    for (int s = 0; s < kSideCount; ++s) {
        RS_CHECK(c[s] <= kSubsamples);
        bits |= uint64_t(c[s]) << (5 + 5 * s);
    }
    // Paper Fig. 3: n ∝ (c₊ₓ − c₋ₓ, c₊ᵧ − c₋ᵧ, c₊z − c₋z), quantized to int8.
    Vec3 n(float(c[kPosX]) - c[kNegX], float(c[kPosY]) - c[kNegY], float(c[kPosZ]) - c[kNegZ]);
    float len = glm::length(n);
    for (int i = 0; i < 3; ++i) {
        int q = len > 0.f ? int(std::lround(n[i] / len * 127.f)) : 0;
        bits |= uint64_t(uint8_t(int8_t(q))) << (35 + 8 * i);
    }
    return Node{bits};
}

namespace {

struct Box {
    IVec3 lo, hi;  // voxels [lo, hi)
};

// Count of interesting voxels in any box in O(1): sat(i, j, k) = count over [0,i)×[0,j)×[0,k).
// Unsigned wrap-around makes the inclusion–exclusion exact.
class SummedAreaTable {
public:
    SummedAreaTable(const IVec3& dims, const std::vector<uint8_t>& flags, ThreadPool& pool)
        : sx_(size_t(dims.x) + 1), sy_(size_t(dims.y) + 1), sz_(size_t(dims.z) + 1), table_(sx_ * sy_ * sz_, 0) {
        const size_t dx = size_t(dims.x), dy = size_t(dims.y), dz = size_t(dims.z);
        // Fill and prefix along x, one (y, z) row a job.
        pool.parallelFor(int64_t(dy * dz), 256, [&](int64_t b, int64_t e, int) {
            for (int64_t r = b; r < e; ++r) {
                size_t y = size_t(r) % dy, z = size_t(r) / dy;
                uint32_t* row = &table_[at(0, y + 1, z + 1)];
                const uint8_t* f = &flags[dx * (y + dy * z)];
                uint32_t sum = 0;
                for (size_t x = 0; x < dx; ++x) row[x + 1] = sum += f[x];
            }
        });
        // Prefix along y, one (x, z) column a job.
        pool.parallelFor(int64_t(sz_ - 1), 1, [&](int64_t b, int64_t e, int) {
            for (int64_t z = b + 1; z < e + 1; ++z)
                for (size_t y = 1; y < sy_; ++y)
                    for (size_t x = 0; x < sx_; ++x) table_[at(x, y, size_t(z))] += table_[at(x, y - 1, size_t(z))];
        });
        // Prefix along z, one y row of columns a job.
        pool.parallelFor(int64_t(sy_), 1, [&](int64_t b, int64_t e, int) {
            for (int64_t y = b; y < e; ++y)
                for (size_t z = 1; z < sz_; ++z)
                    for (size_t x = 0; x < sx_; ++x) table_[at(x, size_t(y), z)] += table_[at(x, size_t(y), z - 1)];
        });
    }

    uint32_t count(const Box& b) const {
        size_t x0 = b.lo.x, y0 = b.lo.y, z0 = b.lo.z, x1 = b.hi.x, y1 = b.hi.y, z1 = b.hi.z;
        return table_[at(x1, y1, z1)] - table_[at(x0, y1, z1)] - table_[at(x1, y0, z1)] - table_[at(x1, y1, z0)] +
               table_[at(x0, y0, z1)] + table_[at(x0, y1, z0)] + table_[at(x1, y0, z0)] - table_[at(x0, y0, z0)];
    }

private:
    size_t at(size_t x, size_t y, size_t z) const { return x + sx_ * (y + sy_ * z); }
    size_t sx_, sy_, sz_;
    std::vector<uint32_t> table_;
};

}  // namespace

void Brick::setSampleBox(const Vec3& lo, const Vec3& hi) {
    auto quantize = [](float x, float pad) {
        return uint16_t(std::clamp(std::floor((x + kBoxOffset) * kBoxScale + pad), 0.f, 65535.f));
    };
    for (int a = 0; a < 3; ++a) {
        sampleBox[a] = quantize(lo[a], -kBoxPad);
        sampleBox[3 + a] = uint16_t(std::min(65535, quantize(hi[a], kBoxPad) + 1));
    }
}

namespace {

// Top-down over boxes of bricks (box coordinates in bricks; nodes and bricks in voxels).
class Builder {
public:
    Builder(const OcclusionGrid& grid, const SummedAreaTable& sat, const std::vector<uint64_t>& sampleKeys,
            const std::vector<uint8_t>& octant, const std::vector<Vec3>& positions, std::vector<uint32_t>& order,
            OcclusionTree& tree)
        : grid_(grid), sat_(sat), keys_(sampleKeys), octant_(octant), positions_(positions), order_(order), tree_(tree),
          brickDims_((grid.geometry.dims + IVec3(kBrickSize - 1)) / kBrickSize) {}

    void build(const Box& box, int depth) {
        maxDepth_ = std::max(maxDepth_, depth);
        if (sat_.count(box) == 0) {
            push(Node::empty());
            return;
        }
        IVec3 ext = box.hi - box.lo;
        if (ext.x == 1 && ext.y == 1 && ext.z == 1) {
            buildBrick(box.lo);
            return;
        }

        // Split plane: spatial median of the longest axis, or the closest interesting slab
        // when one side of the median holds nothing (paper §5).
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (ext[a] > ext[axis]) axis = a;
        int lo = box.lo[axis], hi = box.hi[axis], mid = lo + (hi - lo) / 2;
        auto slabs = [&](int a, int b) {  // interesting bricks in slabs [a, b) of the box
            Box s = box;
            s.lo[axis] = a;
            s.hi[axis] = b;
            return sat_.count(s);
        };
        int plane = mid;
        if (slabs(lo, mid) == 0) {
            // Smallest s ≥ mid whose slab is interesting; the plane goes at its lower face.
            int a = mid, b = hi - 1;
            while (a < b) {
                int m = a + (b - a) / 2;
                if (slabs(mid, m + 1) > 0) b = m;
                else a = m + 1;
            }
            plane = a;
        } else if (slabs(mid, hi) == 0) {
            // Largest s < mid whose slab is interesting; the plane goes at its upper face.
            int a = lo, b = mid - 1;
            while (a < b) {
                int m = a + (b - a + 1) / 2;
                if (slabs(m, mid) > 0) a = m;
                else b = m - 1;
            }
            plane = a + 1;
        }
        RS_CHECK(plane > lo && plane < hi);

        const int planeVoxel = plane * kBrickSize;  // inside the grid: plane < the last brick
        size_t self = push(Node::split(axis, planeVoxel, 0));
        Box lower = box, upper = box;
        lower.hi[axis] = plane;
        upper.lo[axis] = plane;
        build(lower, depth + 1);
        RS_CHECK(tree_.nodes.size() < (size_t(1) << 32));
        tree_.nodes[self] = Node::split(axis, planeVoxel, uint32_t(tree_.nodes.size()));
        build(upper, depth + 1);

        // Collapse a split between two equal Occlusion nodes (uniform, sample-free block).
        std::vector<Node>& nodes = tree_.nodes;
        if (nodes.size() == self + 3 && nodes[self + 1].type() == NodeType::Occlusion &&
            nodes[self + 1].bits == nodes[self + 2].bits) {
            nodes[self] = nodes[self + 1];
            nodes.resize(self + 1);
        }
    }

    int maxDepth() const { return maxDepth_; }

private:
    size_t push(Node n) {
        tree_.nodes.push_back(n);
        return tree_.nodes.size() - 1;
    }

    // One brick: a Brick leaf with its occupied voxels and samples, or an Occlusion leaf when
    // every voxel of it is occupied with the same counts and it holds no samples.
    void buildBrick(const IVec3& b) {
        const GridGeometry& g = grid_.geometry;
        const IVec3 lo = b * kBrickSize, hi = glm::min(lo + IVec3(kBrickSize), g.dims);
        Brick brick;
        brick.firstVoxel = uint32_t(tree_.voxels.size());
        bool uniform = true;
        const uint8_t* first = grid_.voxel(g.index(lo.x, lo.y, lo.z));
        for (int z = lo.z; z < hi.z; ++z)
            for (int y = lo.y; y < hi.y; ++y)
                for (int x = lo.x; x < hi.x; ++x) {
                    size_t i = g.index(x, y, z);
                    uniform = uniform && grid_.occupied(i) && std::equal(first, first + kSideCount, grid_.voxel(i));
                    if (!grid_.occupied(i)) continue;
                    brick.occupied |= uint64_t(1) << ((x - lo.x) + kBrickSize * ((y - lo.y) + kBrickSize * (z - lo.z)));
                }
        // This brick's eye samples: a run of the sorted (brick << 32 | sample) keys.
        const uint64_t index = uint64_t(b.x) + uint64_t(brickDims_.x) * (uint64_t(b.y) + uint64_t(brickDims_.y) * b.z);
        auto from = std::lower_bound(keys_.begin(), keys_.end(), index << 32);
        auto to = from;
        while (to != keys_.end() && (*to >> 32) == index) ++to;
        if (uniform && from == to) {
            push(Node::occlusion(first));
            return;
        }
        // The occupied voxels' occlusion, in bit order (x fastest, then y, then z).
        for (uint64_t bits = brick.occupied; bits; bits &= bits - 1) {
            int bit = __builtin_ctzll(bits);
            IVec3 v = lo + IVec3(bit & 3, (bit >> 2) & 3, bit >> 4);
            const VoxelOcclusion voxel = VoxelOcclusion::of(grid_.voxel(g.index(v.x, v.y, v.z)));
            tree_.voxels.push_back(voxel);
            for (int side = 0; side < kSideCount; ++side)
                if (voxel.count(side)) brick.sides[side] |= uint64_t(1) << bit;
        }
        RS_CHECK(order_.size() + size_t(to - from) < (size_t(1) << 32));
        brick.firstSample = uint32_t(order_.size());
        brick.sampleCount = uint32_t(to - from);
        // By octant (stable: sample order within one).
        uint32_t count[8] = {};
        for (auto it = from; it != to; ++it) ++count[octant_[*it & 0xffffffffu]];
        uint32_t start[8] = {};
        for (int k = 1; k < 8; ++k) start[k] = start[k - 1] + count[k - 1];
        if (brick.divided()) {
            for (int k = 1; k < 8; ++k) brick.octantStart[k - 1] = uint16_t(start[k]);
            for (int k = 0; k < 8; ++k) brick.octantsFilled |= uint8_t(count[k] ? 1u << k : 0u);
        }
        order_.resize(order_.size() + brick.sampleCount);
        uint32_t* out = order_.data() + brick.firstSample;  // (no element when the brick has no samples)
        Vec3 boxLo(INFINITY), boxHi(-INFINITY);
        for (auto it = from; it != to; ++it) {
            const uint32_t i = uint32_t(*it & 0xffffffffu);
            out[brick.divided() ? start[octant_[i]]++ : uint32_t(it - from)] = i;
            const Vec3 p = g.voxelFromWorld(positions_[i]) - Vec3(lo);
            boxLo = glm::min(boxLo, p), boxHi = glm::max(boxHi, p);
        }
        if (from != to) brick.setSampleBox(boxLo, boxHi);
        RS_CHECK(tree_.bricks.size() < (size_t(1) << 32));
        push(Node::brickLeaf(uint32_t(tree_.bricks.size()), brick.firstVoxel));
        tree_.bricks.push_back(brick);
    }

    const OcclusionGrid& grid_;
    const SummedAreaTable& sat_;
    const std::vector<uint64_t>& keys_;
    const std::vector<uint8_t>& octant_;
    const std::vector<Vec3>& positions_;
    std::vector<uint32_t>& order_;
    OcclusionTree& tree_;
    IVec3 brickDims_;
    int maxDepth_ = 0;
};

// Counts by type, the voxels inside collapsed Occlusion nodes and in bricks, by walking the boxes.
void countNodes(const OcclusionTree& tree, OcclusionTreeStats& st) {
    struct Item {
        uint32_t node;
        Box box;
    };
    std::vector<Item> stack{{0, {IVec3(0), tree.geometry.dims}}};
    while (!stack.empty()) {
        Item it = stack.back();
        stack.pop_back();
        const Node& n = tree.nodes[it.node];
        switch (n.type()) {
            case NodeType::Empty: ++st.empty; break;
            case NodeType::Split: {
                ++st.split;
                Box lower = it.box, upper = it.box;
                lower.hi[n.axis()] = upper.lo[n.axis()] = n.plane();
                stack.push_back({n.upperChild(), upper});
                stack.push_back({it.node + 1, lower});
                break;
            }
            case NodeType::Brick:
                ++st.bricks;
                st.brickVoxels += size_t(__builtin_popcountll(tree.bricks[n.brick()].occupied));
                break;
            case NodeType::Occlusion: {
                ++st.occlusion;
                IVec3 e = it.box.hi - it.box.lo;
                size_t voxels = size_t(e.x) * e.y * e.z;
                if (voxels > 1) st.collapsedVoxels += voxels;
                break;
            }
        }
    }
    st.nodes = tree.nodes.size();
    st.bytes = tree.bytes();
}

}  // namespace

void OcclusionTreeStats::report(Stats& stats) const {
    stats.setCount("tree_nodes", double(nodes));
    stats.setCount("tree_nodes_empty", double(empty));
    stats.setCount("tree_nodes_split", double(split));
    stats.setCount("tree_nodes_occlusion", double(occlusion));
    stats.setCount("tree_bricks", double(bricks));
    stats.setCount("tree_brick_voxels", double(brickVoxels));
    stats.setCount("tree_depth", double(depth));
    stats.setCount("tree_mb", double(bytes) / kMB);
}

namespace {

// The index of the brick holding voxel (x, y, z), x fastest.
size_t brickIndexOf(const IVec3& brickDims, int x, int y, int z) {
    return size_t(x >> kBrickShift) +
           size_t(brickDims.x) * (size_t(y >> kBrickShift) + size_t(brickDims.y) * size_t(z >> kBrickShift));
}

// The eye samples inside the grid as (brick << 32 | sample) keys sorted by brick, then sample
// (a counting sort over the bricks, in sample order within one: the order std::sort would give
// these unique keys, in linear time); which samples are inside, and each one's octant of its
// brick.
struct SamplesByBrick {
    std::vector<uint64_t> keys;
    std::vector<uint8_t> inside, octant;
};
SamplesByBrick sortByBrick(const GridGeometry& g, const IVec3& brickDims, const EyeSamples& samples, ThreadPool& pool) {
    const size_t n = samples.size();
    SamplesByBrick out{std::vector<uint64_t>(n), std::vector<uint8_t>(n), std::vector<uint8_t>(n)};
    pool.parallelFor(int64_t(n), 4096, [&](int64_t b, int64_t e, int) {
        for (int64_t i = b; i < e; ++i) {
            Vec3 p = g.voxelFromWorld(samples.position[size_t(i)]);
            Vec3 f = glm::floor(p);
            bool ok = isFinite(p) && f.x >= 0.f && f.y >= 0.f && f.z >= 0.f && f.x < float(g.dims.x) &&
                      f.y < float(g.dims.y) && f.z < float(g.dims.z);
            out.inside[size_t(i)] = ok;
            if (ok) out.octant[size_t(i)] = uint8_t((int(f.x) >> 1 & 1) | (int(f.y) >> 1 & 1) << 1 | (int(f.z) >> 1 & 1) << 2);
            out.keys[size_t(i)] = ok ? uint64_t(brickIndexOf(brickDims, int(f.x), int(f.y), int(f.z))) << 32 | uint64_t(i) : ~uint64_t(0);
        }
    });
    std::vector<uint32_t> start(size_t(brickDims.x) * brickDims.y * brickDims.z + 1, 0);
    size_t insideCount = 0;
    for (size_t i = 0; i < n; ++i)
        if (out.inside[i]) ++start[(out.keys[i] >> 32) + 1], ++insideCount;
    for (size_t b = 1; b < start.size(); ++b) start[b] += start[b - 1];
    std::vector<uint64_t> sorted(insideCount);
    for (size_t i = 0; i < n; ++i)
        if (out.inside[i]) sorted[start[out.keys[i] >> 32]++] = out.keys[i];
    out.keys.swap(sorted);
    return out;
}

// Per brick, whether it is interesting: it holds an occupied voxel or an eye sample.
std::vector<uint8_t> interestingBricks(const OcclusionGrid& grid, const IVec3& brickDims, const std::vector<uint64_t>& keys,
                                       ThreadPool& pool) {
    const GridGeometry& g = grid.geometry;
    std::vector<uint8_t> flags(size_t(brickDims.x) * brickDims.y * brickDims.z);
    pool.parallelFor(int64_t(brickDims.y) * brickDims.z, 16, [&](int64_t b, int64_t e, int) {
        for (int64_t row = b; row < e; ++row) {  // one row of bricks along x
            const int by = int(row % brickDims.y), bz = int(row / brickDims.y);
            for (int z = bz * kBrickSize; z < std::min(g.dims.z, (bz + 1) * kBrickSize); ++z)
                for (int y = by * kBrickSize; y < std::min(g.dims.y, (by + 1) * kBrickSize); ++y)
                    for (int x = 0; x < g.dims.x; ++x)
                        if (grid.occupied(g.index(x, y, z))) flags[brickIndexOf(brickDims, x, y, z)] = 1;
        }
    });
    for (uint64_t k : keys) flags[k >> 32] = 1;
    return flags;
}

}  // namespace

OcclusionTree buildOcclusionTree(const OcclusionGrid& grid, EyeSamples& samples, ThreadPool& pool,
                                 OcclusionTreeStats* statsOut) {
    Timer total;
    OcclusionTreeStats st;
    const GridGeometry& g = grid.geometry;
    if (g.dims.x < 1 || g.dims.y < 1 || g.dims.z < 1 || g.dims.x > kMaxTreeDim || g.dims.y > kMaxTreeDim ||
        g.dims.z > kMaxTreeDim || g.voxelCount() >= (size_t(1) << 32))
        throw Error(ErrorKind::Config, "occlusion tree: grid " + std::to_string(g.dims.x) + "×" +
                                           std::to_string(g.dims.y) + "×" + std::to_string(g.dims.z) +
                                           " is outside 1…" + std::to_string(kMaxTreeDim) + " voxels an axis");
    RS_CHECK(grid.counts.size() == g.voxelCount() * kSideCount);
    RS_CHECK(samples.size() < (size_t(1) << 32));
    const IVec3 brickDims = (g.dims + IVec3(kBrickSize - 1)) / kBrickSize;
    const size_t n = samples.size();

    Timer sortTimer;
    SamplesByBrick byBrick = sortByBrick(g, brickDims, samples, pool);
    st.samplesOutside = n - byBrick.keys.size();
    st.sortSeconds = sortTimer.seconds();

    Timer satTimer;
    SummedAreaTable sat(brickDims, interestingBricks(grid, brickDims, byBrick.keys, pool), pool);
    st.satSeconds = satTimer.seconds();

    Timer buildTimer;
    OcclusionTree tree;
    tree.geometry = g;
    std::vector<uint32_t> order;
    order.reserve(n);
    Builder builder(grid, sat, byBrick.keys, byBrick.octant, samples.position, order, tree);
    builder.build({IVec3(0), brickDims}, 0);
    RS_CHECK(order.size() == byBrick.keys.size());
    tree.sampleCount = uint32_t(order.size());
    for (size_t i = 0; i < n; ++i)
        if (!byBrick.inside[i]) order.push_back(uint32_t(i));
    tree.nodes.shrink_to_fit();
    tree.bricks.shrink_to_fit();
    tree.voxels.shrink_to_fit();
    st.buildSeconds = buildTimer.seconds();

    sortTimer = Timer();
    samples.permute(order, pool);
    st.sortSeconds += sortTimer.seconds();

    st.depth = builder.maxDepth();
    countNodes(tree, st);
    st.totalSeconds = total.seconds();
    if (statsOut) *statsOut = st;
    return tree;
}

}  // namespace rs
