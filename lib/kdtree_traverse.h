// Traversal of a photon cylinder through the occlusion tree (paper §5.1–5.3, docs/design.md §8).
//
// Takes:   the OcclusionTree, the (tree-sorted) EyeSamples, a Cylinder in voxel space, a
//          per-thread TraversalScratch and a visitor visit(uint32_t sample, float V).
// Calls:   visit(i, V) once for every eye sample i the cylinder reaches whose visibility
//          V = 1 − occlusion is > 0, in increasing N-slice order (then kd order). The splat
//          stage does its own kernel weight and normal tests; samples with V = 0 are not
//          handed over.
// Space:   voxel space; the cylinder axis is o + tω, t ∈ [0, L], radius h.
//
// Definitions (the brute force in tests/kdtree_test.cpp implements the same independently):
//  • Bounds (§5.1). The traversal uses the radius h' = h + 0.6 (kOccluderMargin, see
//    "valid cells"). Per axis b, the disc perpendicular to ω has half-extent
//    r_b = h'·sqrt(1 − ω_b²). A voxel box [lo, hi) is *met* when some t ∈ [0, L] has
//    o_a + tω_a ∈ [lo_a − r_a, hi_a + r_a] on all three axes (the disc's bounding box
//    touches the box). Each face gives a one-sided bound on t; the traversal applies a
//    split's face when it descends, so a leaf's t-range equals the one computed from its own
//    six faces, bit for bit. An eye sample p is *reached* when it lies inside the cylinder —
//    depth (p − o)·ω ∈ (0, L] and distance to the axis line < h (d⊥² = |p − o|² −
//    ((p − o)·ω)²) — and, when the origin has a normal n_o, in front of its tangent plane,
//    (p − o)·n_o > 0 (light leaving a surface does not reach the space behind it; at the
//    paper's settings on the glossy box this drops 42 % of the samples a cylinder met,
//    mostly those on the surface the photon leaves). Its voxel is then met (h < h'). Samples
//    outside the kernel get nothing anyway, and their reads would reach cells no occluder
//    was gathered for.
//  • Mask (§5.1). N = the axis of largest |ω| (ties: lowest), U = N+1, V = N+2 (mod 3).
//    A point p maps to u = (p_U − o_U) − (ω_U/ω_N)(p_N − o_N), likewise v: its projection
//    along ω onto the plane through o perpendicular to N. Cell (i, j) = (⌊u⌋, ⌊v⌋), centre
//    (i + ½, j + ½).
//  • Occluders (§5.2). A met, occupied voxel whose box lies strictly in front of the
//    tangent plane at o — (centre − o)·n_o > ½‖n_o‖₁, skipped when n_o = 0 — adds to the
//    cell of its centre's projection the occlusion of its back-facing surfaces along ω:
//    occ = min(1, Σ_a |ω_a|/(16|ω_N|) · c_{a, sign ω_a}) (sides whose normal points along
//    ω_a: the photon meets their back, projected onto the N plane).
//  • Precedence. Slices are voxel layers along N counted in the direction of ω
//    (s = v_N, or dims_N − 1 − v_N when ω_N < 0). An occluder belongs to its slice; an
//    ambiguous one (both signs on an axis, §5.3) to its slice + k with
//    k = clamp(⌈|ω_N| / |ω_D|⌉, 1, 4), D its dominant axis (largest c₊ + c₋): its occlusion
//    distance is pushed one voxel along D (t += 1/|ω_D|, that many N slices), so a thin
//    double-sided surface does not shadow its own lit side. A sample in slice s sees the
//    cells' sums over the occluders of slices < s, each capped at 1 (the cell is full) —
//    never its own voxel's occlusion, nor a neighbour's in the same slice.
//  • Valid cells. A cell is valid when its centre, as a point of the N plane through o,
//    lies within h + 0.71 of the axis line. Every voxel whose centre projects into a valid
//    cell has its centre within h + 0.71 + √2/2 < h' + √3/2 of the axis, so (inside the t
//    range) the voxel is met: a valid cell has all its occluders. A reached sample's nearest
//    cell centre is within √2/2 of it, so it always has a valid neighbour.
//  • V = 1 − bilinear interpolation of those capped cell values between the 4 cell centres
//    nearest to the sample's (u, v), over the valid ones, the weights renormalised. Without
//    the validity rule a sample near the rim would read half-empty cells outside the
//    cylinder and light would leak through walls at small h.
// The definition does not depend on the kd order: the traversal collects the met
// occluders and reached samples, then sweeps them slice by slice. Near-to-far kd order
// (lower child first iff ω_a ≥ 0) serves the early exit: once a node's every sample would
// read full cells and its occluders could only add to full cells — all the cells its
// projection touches were filled by occluders of slices before the node's first slice — it
// is skipped (a wall stops the traversal behind it). Only valid cells count. Cylinder parts
// outside the grid or past L are never visited. At a brick leaf the occupied voxels (its mask's
// bits inside the cylinder part's bounds) that are met become occluders and its samples that
// are reached are collected; a collapsed Occlusion block contributes each of its met voxels.
#pragma once

#include <climits>
#include <cmath>
#include <cstdint>
#include <vector>

#include "eye.h"
#include "kdtree.h"

namespace rs {

struct Cylinder {
    Vec3 origin{0.f};        // o, voxel space
    Vec3 dir{0.f, 0.f, 1.f};  // ω, unit
    float radius = 1.f;       // h, voxels
    float length = 0.f;       // L, voxels
    Vec3 originNormal{0.f};   // n_o, unit normal of the surface the photon leaves; zero if none
};

struct TraversalStats {
    uint64_t cylinders = 0, nodes = 0, pruned = 0, occluders = 0, samplesReached = 0, samplesVisited = 0;
    uint64_t maskOverflow = 0;  // occluders outside the mask (none by construction)
    void add(const TraversalStats& o) {
        cylinders += o.cylinders, nodes += o.nodes, pruned += o.pruned, occluders += o.occluders;
        samplesReached += o.samplesReached, samplesVisited += o.samplesVisited, maskOverflow += o.maskOverflow;
    }
};

constexpr int kMaxAmbiguousOffset = 4;    // N slices
constexpr float kOccluderMargin = 0.6f;   // h' = h + margin gathers the occluders of valid cells
constexpr float kValidCellMargin = 0.71f; // valid cells: centre within h + margin of the axis

namespace kd_detail {

struct StackEntry {
    uint32_t node;
    float t0, t1;
    uint16_t lo[3], hi[3];
};
struct OccluderEvent {
    int32_t cell, slice;
    float occ;
};
struct SampleEvent {
    uint32_t index;
    int32_t slice;
    float u, v;
};
struct FillCell {  // early-exit bookkeeping, valid when stamp matches the cylinder
    uint32_t stamp = 0;
    float sum = 0;
    int32_t maxSlice = INT_MIN, fullAt = INT_MAX;
};

// One face of a box clips the axis parameter range (§5.1): o + tω within r of the face.
inline void clipLowerFace(float o, float w, float r, float lo, float& t0, float& t1) {
    float d = (lo - r) - o;
    if (w > 0.f) t0 = std::max(t0, d / w);
    else if (w < 0.f) t1 = std::min(t1, d / w);
    else if (d > 0.f) t0 = kInf;
}
inline void clipUpperFace(float o, float w, float r, float hi, float& t0, float& t1) {
    float d = (hi + r) - o;
    if (w > 0.f) t1 = std::min(t1, d / w);
    else if (w < 0.f) t0 = std::max(t0, d / w);
    else if (d < 0.f) t0 = kInf;
}

inline int majorAxis(const Vec3& w) {
    int n = 0;
    for (int a = 1; a < 3; ++a)
        if (std::abs(w[a]) > std::abs(w[n])) n = a;
    return n;
}

}  // namespace kd_detail

// Per-thread scratch: the stack, the mask and the event lists grow to the largest cylinder
// seen and are reused, so traversal allocates nothing in steady state.
class TraversalScratch {
public:
    std::vector<kd_detail::StackEntry> stack;
    std::vector<kd_detail::FillCell> fill;
    std::vector<float> sweep;
    std::vector<kd_detail::OccluderEvent> occluders, occludersSorted;
    std::vector<kd_detail::SampleEvent> samples, samplesSorted;
    std::vector<uint32_t> histogram;
    std::vector<int> rowLo, rowHi;  // the valid cells of each mask row
    uint32_t stamp = 0;
};

template <class Visit>
void traverseCylinder(const OcclusionTree& tree, const EyeSamples& eye, const Cylinder& cyl, TraversalScratch& s,
                      Visit&& visit, TraversalStats* statsOut = nullptr) {
    using namespace kd_detail;
    TraversalStats st;
    st.cylinders = 1;
    const GridGeometry& g = tree.geometry;
    const Vec3 o = cyl.origin, w = cyl.dir, n = cyl.originNormal;
    const float L = cyl.length;
    const float invVoxel = 1.f / g.voxelSize;

    // Per-cylinder constants.
    const int N = majorAxis(w), U = (N + 1) % 3, V = (N + 2) % 3;
    float r[3];
    const float hOcc = cyl.radius + kOccluderMargin;
    const float kernel2 = cyl.radius * cyl.radius;
    const float valid2 = sqr(cyl.radius + kValidCellMargin);
    for (int b = 0; b < 3; ++b) r[b] = hOcc * std::sqrt(std::max(0.f, 1.f - w[b] * w[b]));
    const float kU = w[U] / w[N], kV = w[V] / w[N];
    const bool forward = w[N] >= 0.f;
    const int dimN = g.dims[N];
    auto sliceOf = [&](int vN) { return forward ? vN : dimN - 1 - vN; };
    float occWeight[3];
    int side[3], ambOffset[3];
    for (int a = 0; a < 3; ++a) {
        occWeight[a] = std::abs(w[a]) / (16.f * std::abs(w[N]));
        side[a] = w[a] >= 0.f ? 2 * a : 2 * a + 1;
        float wa = std::abs(w[a]);
        ambOffset[a] = wa * kMaxAmbiguousOffset <= std::abs(w[N])
                           ? kMaxAmbiguousOffset
                           : std::min(kMaxAmbiguousOffset, std::max(1, int(std::ceil(std::abs(w[N]) / wa))));
    }
    const bool hasNormal = n.x != 0.f || n.y != 0.f || n.z != 0.f;
    const float tangentOffset = 0.5f * (std::abs(n.x) + std::abs(n.y) + std::abs(n.z));

    // The mask covers every point of every met voxel (|u| ≤ r_U + 1 + (r_N + 1)|k_U|) plus
    // the bilinear neighbours.
    const int halfU = int(std::ceil(r[U] + 1.f + (r[N] + 1.f) * std::abs(kU))) + 2;
    const int halfV = int(std::ceil(r[V] + 1.f + (r[N] + 1.f) * std::abs(kV))) + 2;
    const int sizeU = 2 * halfU, sizeV = 2 * halfV;
    const size_t cells = size_t(sizeU) * sizeV;
    // Cell (i, j), relative to the mask centre: its centre's distance to the axis line.
    auto validCell = [&](int i, int j) {
        Vec3 q(0.f);
        q[U] = float(i) + 0.5f;
        q[V] = float(j) + 0.5f;
        float along = glm::dot(q, w);
        return glm::dot(q, q) - along * along <= valid2;
    };
    if (s.fill.size() < cells) s.fill.resize(cells), s.sweep.resize(cells);
    // The valid cells of each mask row j: [rowLo[j], rowHi[j]] (mask indices, may reach past
    // the mask; empty when rowLo > rowHi). Per row the cells' distance² to the axis is a
    // convex quadratic in i (second difference 2(1 − ω_U²) ≥ 1, far above rounding), so the
    // valid cells are contiguous; the bounds are estimated analytically, then settled with
    // validCell itself so that they agree with it exactly.
    if (s.rowLo.size() < size_t(sizeV)) s.rowLo.resize(size_t(sizeV)), s.rowHi.resize(size_t(sizeV));
    {
        const float qa = 1.f - w[U] * w[U], qb = w[U] * w[V], qc = 1.f - w[V] * w[V];
        for (int j = 0; j < sizeV; ++j) {
            const int jj = j - halfV;
            const float y = float(jj) + 0.5f;
            // Q(x) = qa x² − 2 qb x y + qc y², x = i + ½ (relative to the mask centre).
            const float xc = qb * y / qa;
            int ic = int(std::floor(xc));  // x = ic + ½ is the cell centre nearest the minimum
            if (!validCell(ic, jj)) {
                if (validCell(ic - 1, jj)) --ic;
                else if (validCell(ic + 1, jj)) ++ic;
                else {
                    s.rowLo[size_t(j)] = INT_MAX / 2, s.rowHi[size_t(j)] = INT_MIN / 2;
                    continue;
                }
            }
            const float disc = std::max(0.f, qb * qb * y * y - qa * (qc * y * y - valid2));
            const float half = std::sqrt(disc) / qa;
            int lo = std::min(ic, int(std::floor(xc - half - 0.5f)) + 1);
            int hi = std::max(ic, int(std::floor(xc + half - 0.5f)));
            while (lo < ic && !validCell(lo, jj)) ++lo;
            while (validCell(lo - 1, jj)) --lo;
            while (hi > ic && !validCell(hi, jj)) --hi;
            while (validCell(hi + 1, jj)) ++hi;
            s.rowLo[size_t(j)] = lo + halfU, s.rowHi[size_t(j)] = hi + halfU;
        }
    }
    auto validMaskCell = [&](int i, int j) {  // mask indices; j within the mask
        return i >= s.rowLo[size_t(j)] && i <= s.rowHi[size_t(j)];
    };
    if (++s.stamp == 0) {
        for (FillCell& c : s.fill) c.stamp = 0;
        s.stamp = 1;
    }
    const uint32_t stamp = s.stamp;
    size_t fullCount = 0;
    s.occluders.clear();
    s.samples.clear();

    auto addOccluder = [&](int ix, int iy, int iz, VoxelOcclusion voxel) {
        Vec3 c(float(ix) + 0.5f, float(iy) + 0.5f, float(iz) + 0.5f);
        if (hasNormal && glm::dot(c - o, n) <= tangentOffset) return;
        float occ = 0.f;
        for (int a = 0; a < 3; ++a) occ += occWeight[a] * float(voxel.count(side[a]));
        occ = std::min(1.f, occ);
        if (occ <= 0.f) return;
        int v[3] = {ix, iy, iz};
        int slice = sliceOf(v[N]) + (voxel.ambiguous() ? ambOffset[voxel.dominantAxis()] : 0);
        int cu = int(std::floor((c[U] - o[U]) - kU * (c[N] - o[N]))) + halfU;
        int cv = int(std::floor((c[V] - o[V]) - kV * (c[N] - o[N]))) + halfV;
        if (cu < 0 || cv < 0 || cu >= sizeU || cv >= sizeV) {
            ++st.maskOverflow;
            return;
        }
        int cell = cu + sizeU * cv;
        s.occluders.push_back({cell, slice, occ});
        ++st.occluders;
        FillCell& f = s.fill[size_t(cell)];
        if (f.stamp != stamp) f = FillCell{stamp, 0.f, INT_MIN, INT_MAX};
        if (f.fullAt == INT_MAX) {
            f.sum += occ;
            f.maxSlice = std::max(f.maxSlice, slice);
            if (f.sum >= 1.f) f.fullAt = f.maxSlice, ++fullCount;
        }
    };

    // Bounds of the cylinder part in a node: its t-range's disc boxes, clipped to the node.
    auto nodeBounds = [&](const StackEntry& e, Vec3& lo, Vec3& hi) {
        for (int b = 0; b < 3; ++b) {
            float a0 = o[b] + e.t0 * w[b], a1 = o[b] + e.t1 * w[b];
            lo[b] = std::max(float(e.lo[b]), std::min(a0, a1) - r[b]);
            hi[b] = std::min(float(e.hi[b]), std::max(a0, a1) + r[b]);
        }
    };

    // A voxel is met when the t-range its own six faces allow is not empty (the same range,
    // bit for bit, as the one the splits narrowed down to its leaf). A point within h' of the
    // axis at a depth t ∈ [0, L] lies in that t's disc, whose box then overlaps its voxel's:
    // the voxel is met without the six divisions.
    const float hOcc2 = hOcc * hOcc;
    auto surelyMet = [&](const Vec3& p) {
        const Vec3 d = p - o;
        const float along = glm::dot(d, w);
        return along >= 0.f && along <= L && glm::dot(d, d) - along * along < hOcc2;
    };
    auto voxelMet = [&](int x, int y, int z) {
        float t0 = 0.f, t1 = L;
        const int v[3] = {x, y, z};
        for (int a = 0; a < 3; ++a) {
            clipLowerFace(o[a], w[a], r[a], float(v[a]), t0, t1);
            clipUpperFace(o[a], w[a], r[a], float(v[a] + 1), t0, t1);
        }
        return t0 <= t1;
    };
    // The voxels of a node's box that may be met: the cylinder part's bounds, widened a voxel.
    auto metRange = [&](const StackEntry& e, int i0[3], int i1[3]) {
        Vec3 lo, hi;
        nodeBounds(e, lo, hi);
        for (int b = 0; b < 3; ++b) {
            i0[b] = std::max(int(e.lo[b]), int(std::floor(lo[b])) - 1);
            i1[b] = std::min(int(e.hi[b]), int(std::ceil(hi[b])) + 1);
        }
    };
    // The bits of a brick (whose min corner is e.lo) inside voxel ranges [i0, i1).
    auto brickRangeMask = [](const StackEntry& e, const int i0[3], const int i1[3]) {
        auto axisBits = [](int from, int to) { return to <= from ? 0u : ((1u << to) - 1u) & ~((1u << from) - 1u); };
        uint64_t mask = 0;
        const unsigned xs = axisBits(i0[0] - e.lo[0], i1[0] - e.lo[0]);
        const unsigned ys = axisBits(i0[1] - e.lo[1], i1[1] - e.lo[1]);
        const unsigned zs = axisBits(i0[2] - e.lo[2], i1[2] - e.lo[2]);
        for (int z = 0; z < kBrickSize; ++z) {
            if (!(zs >> z & 1u)) continue;
            for (int y = 0; y < kBrickSize; ++y)
                if (ys >> y & 1u) mask |= uint64_t(xs) << (kBrickSize * (y + kBrickSize * z));
        }
        return mask;
    };

    // Whether octant k of a brick (2×2×2 voxels, its bounding sphere) can hold a reached
    // sample: it reaches into the depth range (0, L], within h of the axis, in front of the
    // origin's tangent plane. It only skips per-sample tests, which decide.
    const float octantRadius = 0.5f * std::sqrt(12.f) + 1e-3f;
    auto octantMayBeReached = [&](const StackEntry& e, int k) {
        const Vec3 c(float(e.lo[0] + 2 * (k & 1) + 1), float(e.lo[1] + (k & 2) + 1), float(e.lo[2] + (k >> 1 & 2) + 1));
        const Vec3 d = c - o;
        const float along = glm::dot(d, w);
        if (along + octantRadius <= 0.f || along - octantRadius > L) return false;
        if (hasNormal && glm::dot(d, n) + octantRadius <= 0.f) return false;
        const float reach = cyl.radius + octantRadius;
        return glm::dot(d, d) - along * along < reach * reach;
    };

    // Early exit: every cell the node's points project to (and their bilinear
    // neighbours) was full before the node's first slice.
    auto prunable = [&](const StackEntry& e) {
        Vec3 lo, hi;
        nodeBounds(e, lo, hi);
        for (int b = 0; b < 3; ++b) lo[b] = std::max(float(e.lo[b]), lo[b] - 1.f), hi[b] = std::min(float(e.hi[b]), hi[b] + 1.f);
        auto range = [&](int A, float k, int half, int& i0, int& i1) {
            float n0 = k * (lo[N] - o[N]), n1 = k * (hi[N] - o[N]);
            float uMin = (lo[A] - o[A]) - std::max(n0, n1), uMax = (hi[A] - o[A]) - std::min(n0, n1);
            i0 = int(std::floor(uMin - 0.5f)) - 1 + half;
            i1 = int(std::floor(uMax - 0.5f)) + 2 + half;
        };
        int u0, u1, v0, v1;
        range(U, kU, halfU, u0, u1);
        range(V, kV, halfV, v0, v1);
        if (u0 < 0 || v0 < 0 || u1 >= sizeU || v1 >= sizeV) return false;
        int firstSlice = forward ? int(e.lo[N]) : dimN - int(e.hi[N]);
        for (int j = v0; j <= v1; ++j) {
            const int i0 = std::max(u0, s.rowLo[size_t(j)]), i1 = std::min(u1, s.rowHi[size_t(j)]);
            const FillCell* row = &s.fill[size_t(sizeU) * size_t(j)];
            for (int i = i0; i <= i1; ++i)
                if (row[i].stamp != stamp || row[i].fullAt >= firstSlice) return false;
        }
        return true;
    };

    // The root: the part of [0, L] whose disc boxes touch the grid.
    StackEntry root{0, 0.f, L, {0, 0, 0}, {uint16_t(g.dims.x), uint16_t(g.dims.y), uint16_t(g.dims.z)}};
    for (int a = 0; a < 3; ++a) {
        clipLowerFace(o[a], w[a], r[a], 0.f, root.t0, root.t1);
        clipUpperFace(o[a], w[a], r[a], float(g.dims[a]), root.t0, root.t1);
    }
    s.stack.clear();
    if (root.t0 <= root.t1) s.stack.push_back(root);

    while (!s.stack.empty()) {
        StackEntry e = s.stack.back();
        s.stack.pop_back();
        ++st.nodes;
        if (fullCount > 0 && prunable(e)) {
            ++st.pruned;
            continue;
        }
        const Node node = tree.nodes[e.node];
        switch (node.type()) {
            case NodeType::Empty: break;
            case NodeType::Split: {
                // Shrink the cylinder bounds to each child; the near child goes on top.
                const int a = node.axis();
                const float plane = float(node.plane());
                StackEntry lower = e, upper = e;
                lower.node = e.node + 1;
                lower.hi[a] = uint16_t(node.plane());
                clipUpperFace(o[a], w[a], r[a], plane, lower.t0, lower.t1);
                upper.node = node.upperChild();
                upper.lo[a] = uint16_t(node.plane());
                clipLowerFace(o[a], w[a], r[a], plane, upper.t0, upper.t1);
                const StackEntry& nearChild = w[a] >= 0.f ? lower : upper;
                const StackEntry& farChild = w[a] >= 0.f ? upper : lower;
                if (farChild.t0 <= farChild.t1) s.stack.push_back(farChild);
                if (nearChild.t0 <= nearChild.t1) s.stack.push_back(nearChild);
                break;
            }
            case NodeType::Brick: {
                // The brick's occupied voxels that the cylinder meets, then its samples.
                const Brick& brick = tree.bricks[node.brick()];
                int i0[3], i1[3];
                metRange(e, i0, i1);
                const uint64_t candidates = brick.occupied & brickRangeMask(e, i0, i1);
                // Walk the occupied bits in order: the rank of a bit is where its counts are.
                uint32_t rank = 0;
                for (uint64_t bits = candidates ? brick.occupied : 0; bits; bits &= bits - 1, ++rank) {
                    const int bit = __builtin_ctzll(bits);
                    if (!(candidates >> bit & 1)) continue;
                    const int x = e.lo[0] + (bit & 3), y = e.lo[1] + ((bit >> 2) & 3), z = e.lo[2] + (bit >> 4);
                    if (!surelyMet(Vec3(float(x) + 0.5f, float(y) + 0.5f, float(z) + 0.5f)) && !voxelMet(x, y, z)) continue;
                    addOccluder(x, y, z, tree.voxels[brick.firstVoxel + rank]);
                }
                for (int k = brick.divided() ? 0 : 7; k < 8; ++k) {
                    const uint32_t first = k == 7 && !brick.divided() ? brick.firstSample : brick.octantBegin(k);
                    const uint32_t last = brick.octantEnd(k);
                    if (first == last || (brick.divided() && !octantMayBeReached(e, k))) continue;
                    for (uint32_t i = first; i < last; ++i) {
                    const Vec3 p = (eye.position[i] - g.origin) * invVoxel;
                    const Vec3 d = p - o;
                    const float along = glm::dot(d, w);
                    if (!(along > 0.f && along <= L) || glm::dot(d, d) - along * along >= kernel2) continue;
                    if (hasNormal && glm::dot(d, n) <= 0.f) continue;
                    // Its voxel (clamped to the brick, where the tree put it) gives its slice.
                    int v[3];
                    for (int a = 0; a < 3; ++a) v[a] = std::clamp(int(std::floor(p[a])), int(e.lo[a]), int(e.hi[a]) - 1);
                    float u = (p[U] - o[U]) - kU * (p[N] - o[N]);
                    float vv = (p[V] - o[V]) - kV * (p[N] - o[N]);
                    s.samples.push_back({i, sliceOf(v[N]), u, vv});
                    ++st.samplesReached;
                    }
                }
                break;
            }
            case NodeType::Occlusion: {
                if (e.hi[0] - e.lo[0] == 1 && e.hi[1] - e.lo[1] == 1 && e.hi[2] - e.lo[2] == 1) {
                    addOccluder(e.lo[0], e.lo[1], e.lo[2], node.voxel());
                    break;
                }
                // A collapsed block: each of its met voxels is an occluder.
                int i0[3], i1[3];
                metRange(e, i0, i1);
                for (int z = i0[2]; z < i1[2]; ++z)
                    for (int y = i0[1]; y < i1[1]; ++y)
                        for (int x = i0[0]; x < i1[0]; ++x)
                            if (voxelMet(x, y, z)) addOccluder(x, y, z, node.voxel());
                break;
            }
        }
    }

    // Sweep slice by slice: a slice's samples read the mask before its occluders enter it.
    auto read = [&](const SampleEvent& ev) {
        float x = ev.u - 0.5f, y = ev.v - 0.5f;
        float fx0 = std::floor(x), fy0 = std::floor(y);
        int i0 = int(fx0) + halfU, j0 = int(fy0) + halfV;
        float fx = x - fx0, fy = y - fy0;
        // Valid cells only, weights renormalised; num ≤ den term by term, so occ ≤ 1 and
        // four full cells give exactly 1.
        float num = 0.f, den = 0.f;
        auto cell = [&](int i, int j, float weight) {
            if (weight <= 0.f) return;
            if (j >= 0 && j < sizeV ? !validMaskCell(i, j) : !validCell(i - halfU, j - halfV)) return;
            float c = i < 0 || j < 0 || i >= sizeU || j >= sizeV ? 0.f : std::min(1.f, s.sweep[size_t(i) + size_t(sizeU) * j]);
            num += weight * c;
            den += weight;
        };
        cell(i0, j0, (1.f - fx) * (1.f - fy));
        cell(i0 + 1, j0, fx * (1.f - fy));
        cell(i0, j0 + 1, (1.f - fx) * fy);
        cell(i0 + 1, j0 + 1, fx * fy);
        return den > 0.f ? 1.f - num / den : 1.f;
    };
    // A sample none of whose four bilinear cells holds an occluder reads 0 whatever its slice:
    // V = 1 at once. Only the others go through the slice sweep.
    auto touched = [&](int i, int j) {
        return i >= 0 && j >= 0 && i < sizeU && j < sizeV && s.fill[size_t(i) + size_t(sizeU) * size_t(j)].stamp == stamp;
    };
    if (!s.occluders.empty()) {
        size_t kept = 0;
        for (const SampleEvent& ev : s.samples) {
            const int i0 = int(std::floor(ev.u - 0.5f)) + halfU, j0 = int(std::floor(ev.v - 0.5f)) + halfV;
            if (touched(i0, j0) || touched(i0 + 1, j0) || touched(i0, j0 + 1) || touched(i0 + 1, j0 + 1)) {
                s.samples[kept++] = ev;
            } else {
                visit(ev.index, 1.f);
                ++st.samplesVisited;
            }
        }
        s.samples.resize(kept);
    }
    if (s.occluders.empty()) {
        for (const SampleEvent& ev : s.samples) visit(ev.index, 1.f);
        st.samplesVisited = s.samples.size();
    } else if (!s.samples.empty()) {
        int sMin = INT_MAX, sMax = INT_MIN;
        for (const SampleEvent& ev : s.samples) sMin = std::min(sMin, ev.slice), sMax = std::max(sMax, ev.slice);
        for (const OccluderEvent& ev : s.occluders) sMax = std::max(sMax, ev.slice);  // later ones are harmless
        // Counting sort of both lists by slice (stable: kd order within a slice).
        const size_t slices = size_t(sMax - sMin + 1);
        auto countingSort = [&](auto& in, auto& out, auto key) {
            s.histogram.assign(slices + 1, 0);
            size_t kept = 0;
            for (const auto& ev : in)
                if (key(ev) >= sMin) ++s.histogram[size_t(key(ev) - sMin) + 1], ++kept;
            for (size_t i = 1; i <= slices; ++i) s.histogram[i] += s.histogram[i - 1];
            out.resize(kept);
            for (const auto& ev : in)
                if (key(ev) >= sMin) out[s.histogram[size_t(key(ev) - sMin)]++] = ev;
        };
        // Occluders before the first sample's slice are read by every sample: add them first.
        for (const OccluderEvent& ev : s.occluders)
            if (ev.slice < sMin) s.sweep[size_t(ev.cell)] += ev.occ;
        countingSort(s.samples, s.samplesSorted, [](const SampleEvent& ev) { return ev.slice; });
        countingSort(s.occluders, s.occludersSorted, [](const OccluderEvent& ev) { return ev.slice; });
        size_t is = 0, io = 0;
        for (int slice = sMin; slice <= sMax && is < s.samplesSorted.size(); ++slice) {
            for (; is < s.samplesSorted.size() && s.samplesSorted[is].slice == slice; ++is) {
                float vis = read(s.samplesSorted[is]);
                if (vis > 0.f) visit(s.samplesSorted[is].index, vis), ++st.samplesVisited;
            }
            for (; io < s.occludersSorted.size() && s.occludersSorted[io].slice == slice; ++io)
                s.sweep[size_t(s.occludersSorted[io].cell)] += s.occludersSorted[io].occ;
        }
        // The sweep mask is all zero between cylinders: clear what this one touched.
        for (const OccluderEvent& ev : s.occluders) s.sweep[size_t(ev.cell)] = 0.f;
    }
    if (statsOut) statsOut->add(st);
}

}  // namespace rs
