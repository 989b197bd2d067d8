// The occlusion tree against the dense grid: the build covers every voxel with the right
// node, keeps each voxel's eye samples contiguous and collapses uniform blocks; the cylinder
// traversal reaches the same eye samples with the same visibility as a brute-force walk over
// the grid (kdtree_traverse.h's definitions, re-implemented here without the tree), and
// walls, holes, lit surfaces and thin double-sided slabs behave as the paper says.
#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <random>
#include <set>

#include "occlusion/cylinder_index.h"
#include "occlusion/kdtree.h"
#include "occlusion/kdtree_traverse.h"

using namespace rs;

namespace {

GridGeometry makeGeometry(IVec3 dims, Vec3 origin = Vec3(-1.3f, 0.2f, 2.f), float voxelSize = 0.25f) {
    GridGeometry g;
    g.dims = dims;
    g.origin = origin;
    g.voxelSize = voxelSize;
    return g;
}

// Eye samples at the given voxel-space points; `pixel` keeps each one's identity.
EyeSamples makeSamples(const GridGeometry& g, const std::vector<Vec3>& pVoxel) {
    EyeSamples s;
    for (size_t i = 0; i < pVoxel.size(); ++i) {
        s.add(g.worldFromVoxel(pVoxel[i]), Vec3(0, 0, 1), Vec3(0, 0, 1), false, uint32_t(i), Vec3(1.f));
    }
    return s;
}

void setCounts(OcclusionGrid& grid, int x, int y, int z, std::initializer_list<std::pair<Side, int>> counts) {
    uint8_t* c = grid.voxel(grid.geometry.index(x, y, z));
    for (auto [side, n] : counts) c[side] = uint8_t(n);
}

// A random grid: occupied voxels with random counts (some ambiguous), a few uniform blocks.
OcclusionGrid randomGrid(std::mt19937& rng, IVec3 dims, float occupiedFraction) {
    OcclusionGrid grid(makeGeometry(dims));
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::uniform_int_distribution<int> count(1, 16);
    for (size_t i = 0; i < grid.geometry.voxelCount(); ++i) {
        if (u01(rng) >= occupiedFraction) continue;
        uint8_t* c = grid.voxel(i);
        for (int a = 0; a < 3; ++a) {
            float r = u01(rng);
            if (r < 0.35f) c[2 * a] = uint8_t(count(rng));
            else if (r < 0.7f) c[2 * a + 1] = uint8_t(count(rng));
            else if (r < 0.8f) c[2 * a] = uint8_t(count(rng)), c[2 * a + 1] = uint8_t(count(rng));  // ambiguous
        }
        if (!grid.occupied(i)) c[kPosZ] = 16;
    }
    std::uniform_int_distribution<int> side(0, 5);
    for (int b = 0; b < 2; ++b) {  // uniform blocks, to be collapsed
        IVec3 lo(int(u01(rng) * dims.x * 0.6f), int(u01(rng) * dims.y * 0.6f), int(u01(rng) * dims.z * 0.6f));
        IVec3 hi = glm::min(dims, lo + IVec3(5, 4, 6));
        uint8_t c[kSideCount] = {};
        c[side(rng)] = 16;
        c[side(rng)] = 9;
        for (int z = lo.z; z < hi.z; ++z)
            for (int y = lo.y; y < hi.y; ++y)
                for (int x = lo.x; x < hi.x; ++x)
                    std::copy(c, c + kSideCount, grid.voxel(grid.geometry.index(x, y, z)));
    }
    return grid;
}

std::vector<Vec3> randomPoints(std::mt19937& rng, IVec3 dims, int n) {
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::vector<Vec3> p;
    for (int i = 0; i < n; ++i) p.push_back(Vec3(u01(rng) * dims.x, u01(rng) * dims.y, u01(rng) * dims.z));
    return p;
}

Vec3 randomDirection(std::mt19937& rng) {
    std::normal_distribution<float> g;
    Vec3 d;
    do d = Vec3(g(rng), g(rng), g(rng));
    while (glm::length(d) < 1e-3f);
    return glm::normalize(d);
}

// ---- Brute force: the definitions of kdtree_traverse.h over the dense grid -------------

// V of every eye sample (by index), 0 when not reached or fully occluded.
std::vector<float> bruteForceVisibility(const OcclusionGrid& grid, const EyeSamples& samples, uint32_t sampleCount,
                                        const Cylinder& cyl) {
    const GridGeometry& g = grid.geometry;
    const Vec3 o = cyl.origin, w = cyl.dir, n = cyl.originNormal;
    int N = 0;
    if (std::abs(w.y) > std::abs(w[N])) N = 1;
    if (std::abs(w.z) > std::abs(w[N])) N = 2;
    const int U = (N + 1) % 3, V = (N + 2) % 3;
    float r[3];
    const float h = cyl.radius, hOcc = h + kOccluderMargin;
    for (int b = 0; b < 3; ++b) r[b] = hOcc * std::sqrt(std::max(0.f, 1.f - w[b] * w[b]));
    auto axisDistance2 = [&](Vec3 d) {  // squared distance of o + d to the axis line
        float along = glm::dot(d, w);
        return glm::dot(d, d) - along * along;
    };
    auto met = [&](IVec3 v) {
        float t0 = 0.f, t1 = cyl.length;
        for (int a = 0; a < 3; ++a) {
            float dLo = (float(v[a]) - r[a]) - o[a], dHi = (float(v[a] + 1) + r[a]) - o[a];
            if (w[a] > 0.f) t0 = std::max(t0, dLo / w[a]), t1 = std::min(t1, dHi / w[a]);
            else if (w[a] < 0.f) t1 = std::min(t1, dLo / w[a]), t0 = std::max(t0, dHi / w[a]);
            else if (dLo > 0.f || dHi < 0.f) return false;
        }
        return t0 <= t1;
    };
    auto slice = [&](int vN) { return w[N] >= 0.f ? vN : g.dims[N] - 1 - vN; };
    auto project = [&](Vec3 p, int A) { return (p[A] - o[A]) - (w[A] / w[N]) * (p[N] - o[N]); };

    // Occluders of every met voxel, walked slice by slice front to back, kept per cell.
    std::map<std::pair<int, int>, std::vector<std::pair<int, float>>> cells;  // cell → (slice, occ)
    bool hasNormal = n != Vec3(0.f);
    for (int sl = 0; sl < g.dims[N]; ++sl) {
        int layer = w[N] >= 0.f ? sl : g.dims[N] - 1 - sl;
        IVec3 v;
        v[N] = layer;
        for (v[V] = 0; v[V] < g.dims[V]; ++v[V])
            for (v[U] = 0; v[U] < g.dims[U]; ++v[U]) {
                size_t i = g.index(v.x, v.y, v.z);
                if (!grid.occupied(i) || !met(v)) continue;
                Vec3 c = Vec3(v) + Vec3(0.5f);
                if (hasNormal && glm::dot(c - o, n) <= 0.5f * (std::abs(n.x) + std::abs(n.y) + std::abs(n.z))) continue;
                const uint8_t* cnt = grid.voxel(i);
                float occ = 0.f;
                for (int a = 0; a < 3; ++a)
                    occ += std::abs(w[a]) / (16.f * std::abs(w[N])) * float(cnt[w[a] >= 0.f ? 2 * a : 2 * a + 1]);
                occ = std::min(1.f, occ);
                if (occ <= 0.f) continue;
                int eff = slice(layer);
                bool ambiguous = (cnt[0] && cnt[1]) || (cnt[2] && cnt[3]) || (cnt[4] && cnt[5]);
                if (ambiguous) {
                    int d = 0;
                    for (int a = 1; a < 3; ++a)
                        if (cnt[2 * a] + cnt[2 * a + 1] > cnt[2 * d] + cnt[2 * d + 1]) d = a;
                    float ratio = std::abs(w[d]) == 0.f ? 1e9f : std::abs(w[N]) / std::abs(w[d]);
                    eff += int(std::min(4.f, std::max(1.f, std::ceil(ratio))));
                }
                cells[{int(std::floor(project(c, U))), int(std::floor(project(c, V)))}].push_back({eff, occ});
            }
    }
    auto validCell = [&](int i, int j) {
        Vec3 q(0.f);
        q[U] = float(i) + 0.5f;
        q[V] = float(j) + 0.5f;
        return axisDistance2(q) <= sqr(h + kValidCellMargin);
    };
    auto cellValue = [&](int i, int j, int sampleSlice) {
        auto it = cells.find({i, j});
        if (it == cells.end()) return 0.f;
        float sum = 0.f;
        for (auto [eff, occ] : it->second)
            if (eff < sampleSlice) sum += occ;
        return std::min(1.f, sum);
    };

    std::vector<float> vis(samples.size(), 0.f);
    for (uint32_t s = 0; s < sampleCount; ++s) {
        Vec3 p = g.voxelFromWorld(samples.position[s]);
        IVec3 v(glm::floor(p));
        const float along = glm::dot(p - o, w);
        if (!(along > 0.f && along <= cyl.length) || axisDistance2(p - o) >= h * h) continue;
        if (hasNormal && glm::dot(p - o, n) <= 0.f) continue;
        EXPECT_TRUE(met(v)) << "a sample inside the cylinder is in a met voxel";
        float x = project(p, U) - 0.5f, y = project(p, V) - 0.5f;
        int i = int(std::floor(x)), j = int(std::floor(y));
        float fx = x - std::floor(x), fy = y - std::floor(y);
        int sl = slice(v[N]);
        float num = 0.f, den = 0.f;
        const float weights[4] = {(1.f - fx) * (1.f - fy), fx * (1.f - fy), (1.f - fx) * fy, fx * fy};
        for (int k = 0; k < 4; ++k) {
            int ci = i + (k & 1), cj = j + (k >> 1);
            if (weights[k] <= 0.f || !validCell(ci, cj)) continue;
            num += weights[k] * cellValue(ci, cj, sl);
            den += weights[k];
        }
        EXPECT_GT(den, 0.f) << "a reached sample without a valid cell";
        vis[s] = den > 0.f ? 1.f - num / den : 1.f;
    }
    return vis;
}

std::vector<float> traverse(const OcclusionTree& tree, const EyeSamples& samples, const Cylinder& cyl,
                            TraversalScratch& scratch, TraversalStats* stats = nullptr) {
    std::vector<float> vis(samples.size(), 0.f);
    std::vector<int> visits(samples.size(), 0);
    TraversalStats st;
    traverseCylinder(tree, samples, cyl, scratch, [&](uint32_t i, float v) {
        vis[i] = v;
        ++visits[i];
    }, &st);
    for (size_t i = 0; i < visits.size(); ++i) EXPECT_LE(visits[i], 1) << "sample " << i << " visited twice";
    // Occluders outside the mask are an RS_DCHECK: the sanitizer build (no NDEBUG) aborts on one.
    if (stats) *stats = st;
    return vis;
}

struct Comparison {
    size_t reached = 0, partial = 0, setMismatch = 0, valueMismatch = 0;
    float maxError = 0.f;
};

Comparison compare(const std::vector<float>& tree, const std::vector<float>& brute) {
    Comparison c;
    for (size_t i = 0; i < tree.size(); ++i) {
        c.reached += brute[i] > 0.f;
        c.partial += brute[i] > 0.f && brute[i] < 1.f;
        if ((tree[i] > 0.f) != (brute[i] > 0.f)) ++c.setMismatch;
        float e = std::abs(tree[i] - brute[i]);
        c.maxError = std::max(c.maxError, e);
        if (e > 1e-6f) ++c.valueMismatch;
    }
    return c;
}

// Every node's box, for checks of the build.
template <class Fn>
void walkTree(const OcclusionTree& tree, Fn&& fn) {
    struct Item {
        uint32_t node;
        IVec3 lo, hi;
    };
    std::vector<Item> stack{{0, IVec3(0), tree.geometry.dims}};
    while (!stack.empty()) {
        Item it = stack.back();
        stack.pop_back();
        const Node& n = tree.nodes[it.node];
        fn(it.node, n, it.lo, it.hi);
        if (n.type() == NodeType::Split) {
            Item lower = it, upper = it;
            lower.node = it.node + 1;
            upper.node = n.upperChild();
            lower.hi[n.axis()] = upper.lo[n.axis()] = n.plane();
            stack.push_back(upper);
            stack.push_back(lower);
        }
    }
}

}  // namespace

// ---- Build ---------------------------------------------------------------------------

TEST(OcclusionTreeBuild, NodeIsEightBytes) {
    static_assert(sizeof(Node) == 8);
    EXPECT_EQ(sizeof(Node), 8u);
    uint8_t c[kSideCount] = {16, 0, 3, 16, 0, 7};
    Node n = Node::occlusion(c);
    EXPECT_EQ(n.type(), NodeType::Occlusion);
    for (int s = 0; s < kSideCount; ++s) EXPECT_EQ(n.count(s), c[s]);
    EXPECT_TRUE(n.ambiguous());  // 3 on +y, 16 on −y
    EXPECT_EQ(n.dominantAxis(), 1);  // 3 + 16 on y
    Vec3 expected = glm::normalize(Vec3(16, 3 - 16, -7));
    EXPECT_NEAR(glm::dot(n.normal(), expected), 1.f, 1e-3f);
    Node s = Node::split(2, 4096, 123456789u);
    EXPECT_EQ(s.type(), NodeType::Split);
    EXPECT_EQ(s.axis(), 2);
    EXPECT_EQ(s.plane(), 4096);
    EXPECT_EQ(s.upperChild(), 123456789u);
    Node b = Node::brickLeaf(4000000000u);
    EXPECT_EQ(b.type(), NodeType::Brick);
    EXPECT_EQ(b.brick(), 4000000000u);
    EXPECT_EQ(b.voxelHint(), Node::kNoVoxelHint);
    Node h = Node::brickLeaf(7u, 123456789u);
    EXPECT_EQ(h.type(), NodeType::Brick);
    EXPECT_EQ(h.brick(), 7u);
    EXPECT_EQ(h.voxelHint(), 123456789u);
    EXPECT_EQ(Node::brickLeaf(7u, 0x40000000u).voxelHint(), Node::kNoVoxelHint);
    // A voxel's occlusion in 32 bits: the same counts, ambiguity and dominant axis.
    VoxelOcclusion v = VoxelOcclusion::of(c), fromNode = n.voxel();
    for (int side = 0; side < kSideCount; ++side) EXPECT_EQ(v.count(side), c[side]);
    EXPECT_TRUE(v.ambiguous());
    EXPECT_EQ(v.dominantAxis(), 1);
    EXPECT_EQ(v.bits, fromNode.bits);
}

TEST(OcclusionTreeBuild, EmptyGridWithoutSamplesIsOneEmptyNode) {
    OcclusionGrid grid(makeGeometry({40, 17, 23}));
    EyeSamples samples;
    ThreadPool pool(2);
    OcclusionTreeStats st;
    OcclusionTree tree = buildOcclusionTree(grid, samples, pool, &st);
    ASSERT_EQ(tree.nodes.size(), 1u);
    EXPECT_EQ(tree.nodes[0].type(), NodeType::Empty);
    EXPECT_EQ(st.empty, 1u);
    EXPECT_EQ(st.bytes, 8u);
}

TEST(OcclusionTreeBuild, UniformSolidBlockCollapsesToOneOcclusionNode) {
    ThreadPool pool(2);
    {
        OcclusionGrid grid(makeGeometry({13, 8, 21}));
        for (size_t i = 0; i < grid.geometry.voxelCount(); ++i) grid.voxel(i)[kPosY] = 16, grid.voxel(i)[kNegX] = 5;
        EyeSamples samples;
        OcclusionTree tree = buildOcclusionTree(grid, samples, pool);
        ASSERT_EQ(tree.nodes.size(), 1u);
        EXPECT_EQ(tree.nodes[0].type(), NodeType::Occlusion);
        EXPECT_EQ(tree.nodes[0].count(kPosY), 16);
        EXPECT_EQ(tree.nodes[0].count(kNegX), 5);
    }
    {
        // A block of whole bricks in empty space: the empty space is cut off, the block
        // collapses. A block that is not brick-aligned stays in bricks.
        OcclusionGrid grid(makeGeometry({32, 32, 32}));
        for (int z = 4; z < 12; ++z)
            for (int y = 8; y < 12; ++y)
                for (int x = 20; x < 28; ++x) setCounts(grid, x, y, z, {{kPosZ, 16}});
        EyeSamples samples;
        OcclusionTreeStats st;
        buildOcclusionTree(grid, samples, pool, &st);
        EXPECT_EQ(st.collapsedVoxels, 8u * 4 * 8);
        EXPECT_LE(st.occlusion, 2u);  // four bricks, collapsed at least in pairs
        EXPECT_EQ(st.bricks, 0u);
        setCounts(grid, 27, 11, 11, {{kNegZ, 3}});  // one voxel differs: its brick is a Brick
        buildOcclusionTree(grid, samples, pool, &st);
        EXPECT_EQ(st.bricks, 1u);
        EXPECT_EQ(st.brickVoxels, 64u);
        EXPECT_EQ(st.collapsedVoxels, 8u * 4 * 8 - 64);
    }
}

// Every voxel is covered by exactly one leaf: an Empty leaf (no occupied voxel), an
// Occlusion leaf (the grid's counts, the same for all its voxels), or a brick whose occupancy
// bits and stored counts are the grid's; every eye sample in the grid belongs to the brick
// holding its voxel, and each brick's samples are contiguous.
TEST(OcclusionTreeBuild, LeavesMatchGridAndSamplesAreContiguousPerBrick) {
    std::mt19937 rng(7);
    ThreadPool pool(3);
    for (int trial = 0; trial < 4; ++trial) {
        IVec3 dims(17 + trial * 5, 23, 11 + trial * 7);
        OcclusionGrid grid = randomGrid(rng, dims, 0.1f + 0.1f * trial);
        std::vector<Vec3> pts = randomPoints(rng, dims, 3000);
        for (int i = 0; i < 300; ++i) pts.push_back(Vec3(pts[size_t(i)]));  // shared voxels
        pts.push_back(Vec3(-0.5f, 3.f, 3.f));                               // outside: moved to the end
        pts.push_back(Vec3(3.f, float(dims.y) + 0.01f, 3.f));
        EyeSamples samples = makeSamples(grid.geometry, pts);
        OcclusionTreeStats st;
        OcclusionTree tree = buildOcclusionTree(grid, samples, pool, &st);
        ASSERT_EQ(samples.size(), pts.size());
        EXPECT_EQ(st.samplesOutside, 2u);
        EXPECT_EQ(tree.sampleCount, pts.size() - 2);
        EXPECT_EQ(samples.pixel[tree.sampleCount], pts.size() - 2);  // outside ones keep their order
        EXPECT_EQ(st.nodes, st.empty + st.split + st.occlusion + st.bricks);
        EXPECT_EQ(st.brickVoxels, tree.voxels.size());

        std::vector<int> leafCover(grid.geometry.voxelCount(), 0);
        std::vector<int> sampleSeen(tree.sampleCount, 0);
        walkTree(tree, [&](uint32_t, const Node& n, IVec3 lo, IVec3 hi) {
            if (n.type() == NodeType::Split) return;
            if (n.type() == NodeType::Brick) {
                EXPECT_EQ(lo % kBrickSize, IVec3(0));
                EXPECT_TRUE(glm::all(glm::equal(hi, glm::min(lo + IVec3(kBrickSize), dims))));
                const Brick& b = tree.bricks[n.brick()];
                // Every sample lies in the brick's sample box, by at least the pad, and the box
                // is tight: within a hundredth of a voxel of the samples' own bounds.
                Vec3 boxLo, boxHi, seenLo(INFINITY), seenHi(-INFINITY);
                b.sampleBounds(Vec3(lo), boxLo, boxHi);
                for (uint32_t s = b.firstSample; s < b.firstSample + b.sampleCount; ++s) {
                    ASSERT_LT(s, tree.sampleCount);
                    ++sampleSeen[s];
                    const Vec3 p = grid.geometry.voxelFromWorld(samples.position[s]);
                    IVec3 v(glm::floor(p));
                    EXPECT_TRUE(glm::all(glm::greaterThanEqual(v, lo)) && glm::all(glm::lessThan(v, hi)));
                    EXPECT_TRUE(glm::all(glm::greaterThanEqual(p, boxLo + 5e-4f)) && glm::all(glm::lessThanEqual(p, boxHi - 5e-4f)))
                        << "sample " << s << " outside its brick's sample box";
                    seenLo = glm::min(seenLo, p), seenHi = glm::max(seenHi, p);
                }
                if (b.sampleCount > 0) {
                    EXPECT_TRUE(glm::all(glm::lessThan(seenLo - boxLo, Vec3(0.01f))) && glm::all(glm::lessThan(boxHi - seenHi, Vec3(0.01f))));
                }
                uint32_t rank = 0;
                for (int z = lo.z; z < hi.z; ++z)
                    for (int y = lo.y; y < hi.y; ++y)
                        for (int x = lo.x; x < hi.x; ++x) {
                            size_t i = grid.geometry.index(x, y, z);
                            ++leafCover[i];
                            int bit = (x - lo.x) + 4 * ((y - lo.y) + 4 * (z - lo.z));
                            EXPECT_EQ(bool(b.occupied >> bit & 1), grid.occupied(i));
                        }
                // The stored counts, in bit order.
                for (uint64_t bits = b.occupied; bits; bits &= bits - 1, ++rank) {
                    int bit = __builtin_ctzll(bits);
                    IVec3 v = lo + IVec3(bit & 3, (bit >> 2) & 3, bit >> 4);
                    size_t i = grid.geometry.index(v.x, v.y, v.z);
                    VoxelOcclusion vo = tree.voxels[b.firstVoxel + rank];
                    for (int side = 0; side < kSideCount; ++side) EXPECT_EQ(vo.count(side), grid.voxel(i)[side]);
                    EXPECT_EQ(vo.ambiguous(), grid.ambiguous(i));
                }
                return;
            }
            for (int z = lo.z; z < hi.z; ++z)
                for (int y = lo.y; y < hi.y; ++y)
                    for (int x = lo.x; x < hi.x; ++x) {
                        size_t i = grid.geometry.index(x, y, z);
                        ++leafCover[i];
                        if (n.type() == NodeType::Empty) {
                            EXPECT_FALSE(grid.occupied(i));
                        } else {
                            for (int side = 0; side < kSideCount; ++side) EXPECT_EQ(n.count(side), grid.voxel(i)[side]);
                            EXPECT_EQ(n.ambiguous(), grid.ambiguous(i));
                        }
                    }
        });
        for (size_t i = 0; i < leafCover.size(); ++i) ASSERT_EQ(leafCover[i], 1) << "voxel " << i;
        for (uint32_t s = 0; s < tree.sampleCount; ++s) ASSERT_EQ(sampleSeen[s], 1) << "sample " << s;
    }
}

TEST(OcclusionTreeBuild, SameTreeAndOrderWhateverTheThreadCount) {
    std::mt19937 rng(11);
    IVec3 dims(37, 29, 31);
    OcclusionGrid grid = randomGrid(rng, dims, 0.2f);
    std::vector<Vec3> pts = randomPoints(rng, dims, 20000);
    EyeSamples a = makeSamples(grid.geometry, pts), b = a;
    ThreadPool one(1), many(4);
    OcclusionTree ta = buildOcclusionTree(grid, a, one), tb = buildOcclusionTree(grid, b, many);
    ASSERT_EQ(ta.nodes.size(), tb.nodes.size());
    for (size_t i = 0; i < ta.nodes.size(); ++i) ASSERT_EQ(ta.nodes[i].bits, tb.nodes[i].bits);
    ASSERT_EQ(ta.bricks.size(), tb.bricks.size());
    EXPECT_EQ(0, std::memcmp(ta.bricks.data(), tb.bricks.data(), ta.bricks.size() * sizeof(Brick)));
    ASSERT_EQ(ta.voxels.size(), tb.voxels.size());
    EXPECT_EQ(0, std::memcmp(ta.voxels.data(), tb.voxels.data(), ta.voxels.size() * sizeof(VoxelOcclusion)));
    EXPECT_EQ(a.pixel, b.pixel);
}

// ---- Traversal -----------------------------------------------------------------------

TEST(OcclusionTreeTraversal, MatchesBruteForceOnRandomGrids) {
    std::mt19937 rng(2024);
    ThreadPool pool(2);
    TraversalScratch scratch;
    Comparison total;
    size_t cylinders = 0, occluded = 0;
    TraversalStats stats;
    for (int trial = 0; trial < 6; ++trial) {
        IVec3 dims(20 + 3 * trial, 26 - trial, 18 + 2 * trial);
        OcclusionGrid grid = randomGrid(rng, dims, 0.04f + 0.03f * trial);
        EyeSamples samples = makeSamples(grid.geometry, randomPoints(rng, dims, 6000));
        OcclusionTree tree = buildOcclusionTree(grid, samples, pool);
        std::uniform_real_distribution<float> u01(0.f, 1.f);
        for (int c = 0; c < 60; ++c) {
            Cylinder cyl;
            cyl.origin = Vec3(u01(rng) * dims.x, u01(rng) * dims.y, u01(rng) * dims.z);
            if (c % 7 == 0) cyl.origin -= Vec3(5.f, 0.f, 3.f);  // starting outside the grid
            cyl.dir = randomDirection(rng);
            if (c % 5 == 0) cyl.dir = Vec3(0.f, c % 10 == 0 ? 1.f : -1.f, 0.f);  // axis-aligned
            cyl.radius = 0.5f + u01(rng) * 5.f;
            cyl.length = u01(rng) * 40.f;
            if (c % 2 == 0) {
                Vec3 nrm = randomDirection(rng);
                cyl.originNormal = glm::dot(nrm, cyl.dir) < 0.f ? -nrm : nrm;
            }
            std::vector<float> brute = bruteForceVisibility(grid, samples, tree.sampleCount, cyl);
            TraversalStats st;
            std::vector<float> got = traverse(tree, samples, cyl, scratch, &st);
            stats.add(st);
            Comparison cmp = compare(got, brute);
            EXPECT_EQ(cmp.setMismatch, 0u) << "trial " << trial << " cylinder " << c;
            EXPECT_EQ(cmp.valueMismatch, 0u) << "trial " << trial << " cylinder " << c << " max error " << cmp.maxError;
            total.reached += cmp.reached;
            total.partial += cmp.partial;
            total.maxError = std::max(total.maxError, cmp.maxError);
            ++cylinders;
            occluded += cmp.partial > 0;
        }
    }
    // The comparison must not be vacuous: many samples reached, many partly occluded.
    EXPECT_GT(total.reached, 10000u);
    EXPECT_GT(total.partial, 1000u);
    EXPECT_GT(occluded, cylinders / 4);  // and in many of the cylinders, not in a few
    std::printf("  %zu cylinders (%zu with partly occluded samples), %zu samples reached (%zu partly occluded, %zu "
                "taken a box at a time), max |ΔV| %.2g\n", cylinders, occluded, total.reached, total.partial,
                size_t(stats.samplesBoxed), double(total.maxError));
}

// Samples on surfaces and wide cylinders, as in a render: many bricks and octants lie wholly
// inside a cylinder, away from every occluder, and are taken without their positions being
// read. What they give must be what testing each sample gives (the brute force).
TEST(OcclusionTreeTraversal, BoxesTakenWholeMatchBruteForceOnSurfaces) {
    std::mt19937 rng(77);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    const IVec3 dims(48, 40, 44);
    OcclusionGrid grid = randomGrid(rng, dims, 0.003f);
    for (int z = 10; z < 22; ++z)  // a slab over part of the floor, shadowing it from above
        for (int x = 8; x < 20; ++x) setCounts(grid, x, 14, z, {{kNegY, 16}});
    std::vector<Vec3> points;
    for (int i = 0; i < 36000; ++i) {
        const float a = u01(rng), b = u01(rng);
        switch (i % 3) {
            case 0: points.push_back(Vec3(a * dims.x, 3.37f, b * dims.z)); break;             // floor
            case 1: points.push_back(Vec3(40.61f, a * dims.y, b * dims.z)); break;            // wall
            default: points.push_back(Vec3(a * 30.f, 6.f + 0.7f * a * 30.f, b * dims.z));  // slope
        }
    }
    EyeSamples samples = makeSamples(grid.geometry, points);
    ThreadPool pool(2);
    OcclusionTree tree = buildOcclusionTree(grid, samples, pool);
    TraversalScratch scratch;
    TraversalStats stats;
    Comparison total;
    for (int c = 0; c < 80; ++c) {
        Cylinder cyl;
        cyl.dir = randomDirection(rng);
        if (c % 2 == 0) {  // leaving the floor, upwards
            cyl.origin = Vec3(u01(rng) * dims.x, 3.37f, u01(rng) * dims.z);
            cyl.originNormal = Vec3(0.f, 1.f, 0.f);
            if (cyl.dir.y < 0.f) cyl.dir.y = -cyl.dir.y;
        } else {
            cyl.origin = Vec3(u01(rng) * dims.x, u01(rng) * dims.y, u01(rng) * dims.z);
        }
        cyl.radius = 4.f + u01(rng) * 8.f;
        cyl.length = 5.f + u01(rng) * 50.f;
        std::vector<float> brute = bruteForceVisibility(grid, samples, tree.sampleCount, cyl);
        TraversalStats st;
        std::vector<float> got = traverse(tree, samples, cyl, scratch, &st);
        stats.add(st);
        Comparison cmp = compare(got, brute);
        EXPECT_EQ(cmp.setMismatch, 0u) << "cylinder " << c;
        EXPECT_EQ(cmp.valueMismatch, 0u) << "cylinder " << c << " max error " << cmp.maxError;
        total.reached += cmp.reached;
        total.partial += cmp.partial;
    }
    // Not vacuous: the boxes hold a good part of the reached samples, and others are shadowed.
    EXPECT_GT(stats.samplesBoxed, stats.samplesReached / 10);
    EXPECT_GT(total.partial, 500u);
    std::printf("  %zu samples reached, %zu taken a box at a time, %zu partly occluded\n", total.reached,
                size_t(stats.samplesBoxed), total.partial);
}

namespace {

// A random cylinder of radius 0.5 + U(0, spread) and length U(0, 60): leaving the floor y = 3.37
// (normal +y, into the upper half-space) when `fromFloor`, else from anywhere in the grid.
Cylinder floorOrFreeCylinder(std::mt19937& rng, IVec3 dims, bool fromFloor, float spread) {
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    Cylinder cyl;
    cyl.dir = randomDirection(rng);
    if (fromFloor) {
        cyl.origin = Vec3(u01(rng) * dims.x, 3.37f, u01(rng) * dims.z);
        cyl.originNormal = Vec3(0.f, 1.f, 0.f);
        if (cyl.dir.y < 0.f) cyl.dir.y = -cyl.dir.y;
    } else {
        cyl.origin = Vec3(u01(rng) * dims.x, u01(rng) * dims.y, u01(rng) * dims.z);
    }
    cyl.radius = 0.5f + u01(rng) * spread;
    cyl.length = u01(rng) * 60.f;
    return cyl;
}

}  // namespace

// The sixteen-lane sample step (CPUs with AVX-512) against the four-lane one: the same visits,
// in the same order, with the same V to the bit, on random grids (random points, ranges of every
// length) and on surfaces leaving and meeting walls. The brute-force tests above check
// whichever path this CPU takes.
TEST(OcclusionTreeTraversal, WideSampleStepGivesTheFourLaneAnswersBitForBit) {
    ScopedTraversalIsa restore(traversalIsa());  // the choice comes back however the test ends
    if (!setTraversalIsa(Isa::Avx512)) GTEST_SKIP() << "this CPU has no AVX-512: only the four-lane path runs here";
    std::mt19937 rng(91);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    ThreadPool pool(2);
    TraversalScratch scratch;
    size_t visits = 0, partial = 0;
    for (int scene = 0; scene < 4; ++scene) {
        const IVec3 dims(40, 36, 44);
        OcclusionGrid grid = randomGrid(rng, dims, scene < 2 ? 0.05f : 0.004f);
        std::vector<Vec3> points = randomPoints(rng, dims, 12000);
        for (int i = 0; i < 12000; ++i) {  // a floor and a wall, as surfaces give them
            const float a = u01(rng), b = u01(rng);
            points.push_back(i % 2 ? Vec3(a * dims.x, 3.37f, b * dims.z) : Vec3(30.61f, a * dims.y, b * dims.z));
        }
        EyeSamples samples = makeSamples(grid.geometry, points);
        OcclusionTree tree = buildOcclusionTree(grid, samples, pool);
        for (int c = 0; c < 60; ++c) {
            const Cylinder cyl = floorOrFreeCylinder(rng, dims, c % 3 == 0, c % 2 ? 10.f : 3.f);
            std::vector<std::pair<uint32_t, float>> seen[2];
            for (int wide = 0; wide < 2; ++wide) {
                ASSERT_TRUE(setTraversalIsa(wide == 1 ? Isa::Avx512 : Isa::Sse2));
                traverseCylinder(tree, samples, cyl, scratch, [&](uint32_t i, float v) { seen[wide].push_back({i, v}); });
            }
            ASSERT_EQ(seen[0].size(), seen[1].size()) << "scene " << scene << " cylinder " << c;
            for (size_t k = 0; k < seen[0].size(); ++k) {
                ASSERT_EQ(seen[0][k].first, seen[1][k].first) << "scene " << scene << " cylinder " << c << " visit " << k;
                ASSERT_EQ(std::memcmp(&seen[0][k].second, &seen[1][k].second, sizeof(float)), 0)
                    << "scene " << scene << " cylinder " << c << " sample " << seen[0][k].first;
                partial += seen[0][k].second < 1.f;
            }
            visits += seen[0].size();
        }
    }
    EXPECT_GT(visits, 20000u);  // not vacuous
    EXPECT_GT(partial, 1000u);
    std::printf("  %zu visits (%zu partly occluded) the same on both paths\n", visits, partial);
}

// The mask's valid cells as the sixteen-lane set-up finds them (every cell tested, the rows
// that may reach past the mask left to the row-by-row search) against the row-by-row search
// alone: the same ranges and the same sweep mask (0 in valid cells, kInvalidCell elsewhere),
// for axis-aligned, diagonal and random directions and radii from half a voxel to forty.
TEST(OcclusionTreeTraversal, WideValidCellsAreTheFourLaneOnes) {
    ScopedTraversalIsa restore(traversalIsa());  // the choice comes back however the test ends
    if (!setTraversalIsa(Isa::Avx512)) GTEST_SKIP() << "this CPU has no AVX-512: only the four-lane path runs here";
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::normal_distribution<float> gauss;
    ThreadPool pool(1);
    const IVec3 dims(24, 24, 24);
    OcclusionGrid grid = randomGrid(rng, dims, 0.02f);
    EyeSamples samples = makeSamples(grid.geometry, randomPoints(rng, dims, 500));
    OcclusionTree tree = buildOcclusionTree(grid, samples, pool);
    size_t rows = 0, validCells = 0;
    for (int c = 0; c < 3000; ++c) {
        Cylinder cyl;
        cyl.origin = Vec3(u01(rng), u01(rng), u01(rng)) * Vec3(dims);
        if (c % 5 == 0) cyl.dir = Vec3(0.f), cyl.dir[c % 3] = c % 2 ? 1.f : -1.f;  // along an axis
        else if (c % 5 == 1) cyl.dir = glm::normalize(Vec3(c % 2 ? 1.f : -1.f, 1.f, c % 3 ? 1.f : -1.f));
        else cyl.dir = glm::normalize(Vec3(gauss(rng), gauss(rng), gauss(rng)));
        cyl.radius = 0.5f + 39.5f * u01(rng) * u01(rng);
        cyl.length = 10.f;
        TraversalScratch scratch[2];
        for (int wide = 0; wide < 2; ++wide) {
            ASSERT_TRUE(setTraversalIsa(wide == 1 ? Isa::Avx512 : Isa::Sse2));
            CylinderTraversal traversal(tree, samples, cyl, scratch[wide]);
        }
        ASSERT_EQ(scratch[0].rows.size(), scratch[1].rows.size());
        for (size_t j = 0; j < scratch[0].rows.size(); ++j) {
            ASSERT_EQ(scratch[0].rows[j].lo, scratch[1].rows[j].lo) << "cylinder " << c << " row " << j;
            ASSERT_EQ(scratch[0].rows[j].hi, scratch[1].rows[j].hi) << "cylinder " << c << " row " << j;
        }
        ASSERT_EQ(scratch[0].sweep, scratch[1].sweep) << "cylinder " << c;
        rows += scratch[0].rows.size();
        validCells += size_t(std::count(scratch[0].sweep.begin(), scratch[0].sweep.end(), 0.f));
    }
    EXPECT_GT(rows, 30000u);  // not vacuous
    EXPECT_GT(validCells, 100000u);
}

// A visitor of lists (as the splat's: V = 1 a brick at a time, the swept samples that see light
// a read at a time, the samples ahead announced) gets the same visits, in the same order, with
// the same V to the bit, as one taking them one by one; and each after it was told of it. On
// every path this CPU has.
TEST(OcclusionTreeTraversal, VisitorOfListsGetsTheSameVisits) {
    ScopedTraversalIsa restore(traversalIsa());
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    ThreadPool pool(2);
    TraversalScratch scratch;
    const IVec3 dims(40, 36, 44);
    OcclusionGrid grid = randomGrid(rng, dims, 0.03f);
    std::vector<Vec3> points = randomPoints(rng, dims, 12000);
    for (int i = 0; i < 12000; ++i) points.push_back(Vec3(u01(rng) * dims.x, 3.37f, u01(rng) * dims.z));  // a floor
    EyeSamples samples = makeSamples(grid.geometry, points);
    OcclusionTree tree = buildOcclusionTree(grid, samples, pool);
    size_t visits = 0, lists = 0, partial = 0;
    for (int wide = 0; wide < 2; ++wide) {
        if (!setTraversalIsa(wide == 1 ? Isa::Avx512 : Isa::Sse2)) continue;  // no AVX-512: the four-lane path only
        for (int c = 0; c < 60; ++c) {
            const Cylinder cyl = floorOrFreeCylinder(rng, dims, c % 2 == 0, 8.f);
            std::vector<std::pair<uint32_t, float>> single, listed;
            traverseCylinder(tree, samples, cyl, scratch, [&](uint32_t i, float v) { single.push_back({i, v}); });
            auto take = [&](uint32_t i, float v) { listed.push_back({i, v}); };
            traverseCylinder(tree, samples, cyl, scratch,
                             Overloaded{[&](uint32_t i, float v) { take(i, v); },
                                        [&](const uint32_t* index, size_t count) {
                                            for (size_t k = 0; k < count; ++k) take(index[k], 1.f);
                                        },
                                        [&](const uint32_t* index, const float* v, size_t count) {
                                            EXPECT_GE(count, 1u);
                                            EXPECT_LE(count, 16u);
                                            for (size_t k = 0; k < count; ++k) take(index[k], v[k]);
                                            ++lists;
                                        }});
            ASSERT_EQ(listed.size(), single.size()) << "path " << wide << " cylinder " << c;
            for (size_t k = 0; k < listed.size(); ++k) {
                ASSERT_EQ(listed[k].first, single[k].first) << "path " << wide << " cylinder " << c << " visit " << k;
                ASSERT_EQ(std::memcmp(&listed[k].second, &single[k].second, sizeof(float)), 0)
                    << "path " << wide << " cylinder " << c << " sample " << single[k].first;
                partial += single[k].second < 1.f;
            }
            visits += single.size();
        }
    }
    EXPECT_GT(visits, 10000u);  // not vacuous
    EXPECT_GT(partial, 500u);
    EXPECT_GT(lists, 100u);
    std::printf("  %zu visits (%zu partly occluded, in %zu lists) the same one by one and as lists\n", visits, partial, lists);
}

namespace {

// A 32³ grid, a wall z = 16 whose surfaces face +z (the back seen by light going +z), eye
// samples spread through the grid.
struct WallScene {
    OcclusionGrid grid{makeGeometry({32, 32, 32}, Vec3(0.f), 1.f)};
    EyeSamples samples;
    OcclusionTree tree;

    explicit WallScene(bool wall, IVec3 holeLo = IVec3(0), IVec3 holeHi = IVec3(0)) {
        if (wall)
            for (int y = 0; y < 32; ++y)
                for (int x = 0; x < 32; ++x)
                    if (!(x >= holeLo.x && x < holeHi.x && y >= holeLo.y && y < holeHi.y)) setCounts(grid, x, y, 16, {{kPosZ, 16}});
        std::mt19937 rng(5);
        samples = makeSamples(grid.geometry, randomPoints(rng, grid.geometry.dims, 40000));
        ThreadPool pool(2);
        tree = buildOcclusionTree(grid, samples, pool);
    }
};

float distanceToAxis(const Cylinder& c, Vec3 p) {
    Vec3 d = p - c.origin;
    return glm::length(d - glm::dot(d, c.dir) * c.dir);
}

}  // namespace

TEST(OcclusionTreeTraversal, SolidWallStopsEverythingBehindIt) {
    WallScene scene(true);
    TraversalScratch scratch;
    for (Vec3 dir : {Vec3(0, 0, 1), glm::normalize(Vec3(0.3f, -0.2f, 1.f)), glm::normalize(Vec3(-0.6f, 0.5f, 1.f))}) {
        Cylinder cyl;
        cyl.origin = Vec3(16.f, 15.f, 2.f);
        cyl.dir = dir;
        cyl.radius = 3.f;
        cyl.length = 29.f / dir.z;
        TraversalStats st;
        std::vector<float> v = traverse(scene.tree, scene.samples, cyl, scratch, &st);
        Comparison cmp = compare(v, bruteForceVisibility(scene.grid, scene.samples, scene.tree.sampleCount, cyl));
        EXPECT_EQ(cmp.setMismatch + cmp.valueMismatch, 0u);
        size_t front = 0, behind = 0, behindInside = 0;
        for (uint32_t i = 0; i < scene.tree.sampleCount; ++i) {
            Vec3 p = scene.samples.position[i];
            bool inside = distanceToAxis(cyl, p) < cyl.radius;
            if (p.z < 16.f) front += inside && v[i] == 1.f;
            if (p.z >= 17.f) behind += v[i] > 0.f, behindInside += inside;
        }
        EXPECT_GT(front, 100u);
        EXPECT_GT(behindInside, 100u);
        EXPECT_EQ(behind, 0u) << "samples lit behind the wall";
        std::printf("  dir (%.2f %.2f %.2f): occluders %llu, samples reached %llu, nodes %llu\n", double(dir.x),
                    double(dir.y), double(dir.z), (unsigned long long)st.occluders, (unsigned long long)st.samplesReached,
                    (unsigned long long)st.nodes);
    }
}

TEST(OcclusionTreeTraversal, WallWithHoleLetsLightOnlyThroughTheHole) {
    const IVec3 holeLo(10, 12, 0), holeHi(18, 20, 0);
    WallScene scene(true, holeLo, holeHi);
    TraversalScratch scratch;
    for (Vec3 dir : {Vec3(0, 0, 1), glm::normalize(Vec3(0.25f, -0.15f, 1.f))}) {
        Cylinder cyl;
        cyl.origin = Vec3(14.3f, 15.6f, 3.f) - dir * 13.f / dir.z + Vec3(0, 0, 13.f);
        cyl.origin.z = 3.f;
        cyl.dir = dir;
        cyl.radius = 7.f;
        cyl.length = 28.f / dir.z;
        std::vector<float> v = traverse(scene.tree, scene.samples, cyl, scratch);
        Comparison cmp = compare(v, bruteForceVisibility(scene.grid, scene.samples, scene.tree.sampleCount, cyl));
        EXPECT_EQ(cmp.setMismatch + cmp.valueMismatch, 0u);
        size_t lit = 0, fullyLit = 0, shadowed = 0;
        for (uint32_t i = 0; i < scene.tree.sampleCount; ++i) {
            Vec3 p = scene.samples.position[i];
            const float along = glm::dot(p - cyl.origin, cyl.dir);  // voxel size 1, origin 0
            if (p.z < 17.f || distanceToAxis(cyl, p) >= cyl.radius || along > cyl.length) continue;
            // Where the line from the sample back along ω crosses the wall's mid-plane.
            Vec3 q = p - dir * (p.z - 16.5f) / dir.z;
            auto inHole = [&](float margin) {
                return q.x > holeLo.x + margin && q.x < holeHi.x - margin && q.y > holeLo.y + margin && q.y < holeHi.y - margin;
            };
            if (v[i] > 0.f) {
                ++lit;
                EXPECT_TRUE(inHole(-2.f)) << "lit at (" << q.x << ", " << q.y << ")";
            } else {
                ++shadowed;
            }
            if (inHole(2.f)) {
                EXPECT_EQ(v[i], 1.f);
                ++fullyLit;
            }
        }
        EXPECT_GT(fullyLit, 50u);
        EXPECT_GT(shadowed, 200u);
        EXPECT_GT(lit, fullyLit);
    }
}

TEST(OcclusionTreeTraversal, LitSurfaceDoesNotShadowItself) {
    // A floor z = 10 facing +z, eye samples on it (and in the layer above its voxels).
    OcclusionGrid grid(makeGeometry({32, 32, 32}, Vec3(0.f), 1.f));
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) setCounts(grid, x, y, 10, {{kPosZ, 16}});
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u01(0.f, 32.f);
    std::vector<Vec3> pts;
    for (int i = 0; i < 20000; ++i) pts.push_back(Vec3(u01(rng), u01(rng), i % 2 ? 10.5f : 10.99f));
    EyeSamples samples = makeSamples(grid.geometry, pts);
    ThreadPool pool(2);
    OcclusionTree tree = buildOcclusionTree(grid, samples, pool);
    TraversalScratch scratch;
    std::vector<Cylinder> cylinders;
    // From points above the floor, down onto it.
    for (Vec3 dir : {Vec3(0, 0, -1), glm::normalize(Vec3(0.5f, 0.3f, -1.f)), glm::normalize(Vec3(-2.f, 0.4f, -1.f))}) {
        Cylinder c;
        c.origin = Vec3(16.f, 16.f, 10.75f) - dir * 12.f;
        c.dir = dir;
        c.radius = 4.f;
        c.length = 40.f;
        cylinders.push_back(c);
    }
    // From the floor itself, leaving it (n_o = its normal), grazing and steep.
    for (Vec3 dir : {glm::normalize(Vec3(1.f, 0.2f, 0.3f)), glm::normalize(Vec3(-0.3f, 1.f, 0.8f)), Vec3(0, 0, 1)}) {
        Cylinder c;
        c.origin = Vec3(6.f, 5.f, 10.75f);
        c.dir = dir;
        c.radius = 3.f;
        c.length = 40.f;
        c.originNormal = Vec3(0, 0, 1);
        cylinders.push_back(c);
    }
    for (const Cylinder& c : cylinders) {
        std::vector<float> v = traverse(tree, samples, c, scratch);
        std::vector<float> brute = bruteForceVisibility(grid, samples, tree.sampleCount, c);
        size_t reached = 0;
        for (uint32_t i = 0; i < tree.sampleCount; ++i) {
            if (brute[i] > 0.f || v[i] > 0.f) ++reached;
            EXPECT_EQ(v[i], brute[i]);
            if (brute[i] > 0.f) {
                EXPECT_EQ(v[i], 1.f);
            }
        }
        // Reached = every sample whose voxel the cylinder meets, all with V = 1.
        size_t met = 0;
        TraversalStats st;
        traverseCylinder(tree, samples, c, scratch, [&](uint32_t, float) {}, &st);
        met = st.samplesReached;
        EXPECT_EQ(reached, met);
        EXPECT_GT(reached, 20u);
    }
}

TEST(OcclusionTreeTraversal, ThinDoubleSidedSlabDoesNotShadowItsLitSide) {
    // A thin double-sided slab in voxel layer z = 12 (x, y in [6, 26)): ambiguous voxels with
    // both z sides full; a floor z = 3 below it. Eye samples on the slab's top and the floor.
    OcclusionGrid grid(makeGeometry({32, 32, 32}, Vec3(0.f), 1.f));
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            setCounts(grid, x, y, 3, {{kPosZ, 16}});
            if (x >= 6 && x < 26 && y >= 6 && y < 26) setCounts(grid, x, y, 12, {{kPosZ, 16}, {kNegZ, 16}});
        }
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    std::vector<Vec3> pts;
    for (int i = 0; i < 20000; ++i) {
        float x = u01(rng) * 32.f, y = u01(rng) * 32.f;
        bool onSlab = x >= 6 && x < 26 && y >= 6 && y < 26 && i % 2;
        pts.push_back(Vec3(x, y, onSlab ? 12.6f : 3.5f));
    }
    EyeSamples samples = makeSamples(grid.geometry, pts);
    ThreadPool pool(2);
    OcclusionTree tree = buildOcclusionTree(grid, samples, pool);
    ASSERT_TRUE(grid.ambiguous(grid.geometry.index(10, 10, 12)));
    TraversalScratch scratch;
    for (Vec3 dir : {Vec3(0, 0, -1), glm::normalize(Vec3(0.4f, 0.3f, -1.f)), glm::normalize(Vec3(1.f, 0.2f, -0.8f))}) {
        Cylinder c;
        c.origin = Vec3(16.f, 16.f, 12.6f) - dir * 10.f / -dir.z;
        c.dir = dir;
        c.radius = 5.f;
        c.length = 40.f;
        const bool majorAxisIsZ = std::abs(dir.z) > std::max(std::abs(dir.x), std::abs(dir.y));
        std::vector<float> v = traverse(tree, samples, c, scratch);
        Comparison cmp = compare(v, bruteForceVisibility(grid, samples, tree.sampleCount, c));
        EXPECT_EQ(cmp.setMismatch + cmp.valueMismatch, 0u);
        size_t top = 0, under = 0;
        for (uint32_t i = 0; i < tree.sampleCount; ++i) {
            Vec3 p = samples.position[i];
            if (distanceToAxis(c, p) >= c.radius) continue;
            if (p.z > 12.f) {
                ++top;
                EXPECT_EQ(v[i], 1.f) << "slab top at (" << p.x << ", " << p.y << ") dir " << dir.x << " " << dir.z;
            } else {
                // Floor samples whose line back to the light crosses the slab well inside.
                Vec3 q = p - dir * (p.z - 12.5f) / dir.z;
                if (q.x > 8 && q.x < 24 && q.y > 8 && q.y < 24) {
                    ++under;
                    // With N = z each slab voxel fills its cell. At a grazing angle (N = x) a
                    // voxel's top projects to |ω_z/ω_x| = 0.8 of a cell but counts whole in
                    // the cell of its centre: cells get one voxel (0.8) or two (full).
                    if (majorAxisIsZ) {
                        EXPECT_EQ(v[i], 0.f) << "floor under the slab lit";
                    } else {
                        EXPECT_LE(v[i], 1.f - 0.8f + 1e-6f) << "floor under the slab lit";
                    }
                }
            }
        }
        EXPECT_GT(top, 50u);
        EXPECT_GT(under, 50u);
    }
}


// The receivers' index returns every point inside a cylinder (depth in (begin, end], distance
// from the axis below the radius, in double precision), each once, and nothing past a hundredth
// of the radius outside it: points on planes, a thin rod and scattered (and two not finite, never
// found), cylinders of every direction (some along the axes, where the slabs divide by zero) and
// length.
TEST(CylinderIndex, FindsEveryPointInsideAndLittleMore) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::vector<Vec3> points;
    for (int i = 0; i < 3000; ++i) points.emplace_back(4.f * u(rng), 0.f, 3.f * u(rng));            // a floor
    for (int i = 0; i < 2000; ++i) points.emplace_back(4.f, 2.5f * u(rng), 3.f * u(rng));           // a wall
    for (int i = 0; i < 500; ++i) points.emplace_back(2.f + 0.01f * u(rng), 2.f * u(rng), 1.5f);    // a rod
    for (int i = 0; i < 1003; ++i) points.emplace_back(4.f * u(rng), 2.5f * u(rng), 3.f * u(rng));  // anywhere
    points.insert(points.begin() + 1234, Vec3(NAN, 1.f, 1.f));  // never found, whatever the cylinder
    points.emplace_back(2.f, INFINITY, 1.f);
    const CylinderIndex index(points);
    int found = 0;
    for (int q = 0; q < 2000; ++q) {
        const Vec3 o(4.f * u(rng), 2.5f * u(rng), 3.f * u(rng));
        Vec3 w(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f);
        if (q % 7 == 0) w = Vec3(0.f), w[q % 3] = q % 2 ? 1.f : -1.f;
        w = glm::normalize(w);
        const float radius = 0.02f + 0.3f * u(rng), begin = -0.5f + u(rng), end = begin + 4.f * u(rng);
        std::vector<uint32_t> out;
        CylinderIndex::Counts counts;
        index.query(o, w, radius, begin, end, out, counts);
        std::set<uint32_t> got(out.begin(), out.end());
        ASSERT_EQ(got.size(), out.size()) << "query " << q << ": a point twice";
        for (uint32_t i = 0; i < points.size(); ++i) {
            const glm::dvec3 d = glm::dvec3(points[i]) - glm::dvec3(o), dw(w);
            const double t = glm::dot(d, dw), across = glm::length(glm::cross(d, dw));
            if (t > begin && t <= end && across < radius) {
                EXPECT_TRUE(got.count(i)) << "query " << q << ": point " << i << " inside, not found";
                ++found;
            } else if (got.count(i)) {
                const double out2 = std::max({across - radius, begin - t, t - end});
                EXPECT_LT(out2, 0.011 * radius) << "query " << q << ": point " << i << " far outside";
            }
        }
        EXPECT_LE(counts.points, points.size() + CylinderIndex::kFan);
    }
    EXPECT_GT(found, 20000);
    const CylinderIndex none{std::vector<Vec3>()};
    std::vector<uint32_t> out;
    CylinderIndex::Counts counts;
    none.query(Vec3(0.f), Vec3(1.f, 0.f, 0.f), 1.f, 0.f, 10.f, out, counts);
    EXPECT_TRUE(out.empty());
}
