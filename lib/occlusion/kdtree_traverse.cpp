// The steps of CylinderTraversal that set up its mask and gather occluders and samples
// (kdtree_traverse.h states the rules they implement); reaching the samples and the slice sweep
// are in kdtree_reach.cpp.
#include "occlusion/kdtree_traverse.h"

#include <numeric>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace rs {

using namespace kd_detail;

// -- Mask set-up (§5.1) -----------------------------------------------------------------------

CylinderTraversal::CylinderTraversal(const OcclusionTree& tree, const EyeSamples& eye, const Cylinder& cyl,
                                     TraversalScratch& s)
    : tree_(tree), eye_(eye), g_(tree.geometry), s_(s), o_(cyl.origin), w_(cyl.dir), n_(cyl.originNormal),
      L_(cyl.length), radius_(cyl.radius), invVoxel_(1.f / tree.geometry.voxelSize) {
    st_.cylinders = 1;
    N_ = majorAxis(w_), U_ = (N_ + 1) % 3, V_ = (N_ + 2) % 3;
    hOcc_ = radius_ + kOccluderMargin;
    kernel2_ = radius_ * radius_;
    valid2_ = sqr(radius_ + kValidCellMargin);
    discHalfExtents(w_, hOcc_, r_);
    kU_ = w_[U_] / w_[N_], kV_ = w_[V_] / w_[N_];
    aU_ = Vec3(0.f), aV_ = Vec3(0.f);
    aU_[U_] = 1.f, aU_[N_] = -kU_;
    aV_[V_] = 1.f, aV_[N_] = -kV_;
    absW_ = glm::abs(w_), absN_ = glm::abs(n_), absAU_ = glm::abs(aU_), absAV_ = glm::abs(aV_);
    forward_ = w_[N_] >= 0.f;
    dimN_ = g_.dims[N_];
    // Occluders: the back-facing sides along ω, projected onto the N plane; ambiguous voxels
    // pushed one voxel along their dominant axis D, that many N slices (§5.3).
    for (int a = 0; a < 3; ++a) {
        occWeight_[a] = std::abs(w_[a]) / (float(kSubsamples) * std::abs(w_[N_]));
        side_[a] = w_[a] >= 0.f ? 2 * a : 2 * a + 1;
        const float wa = std::abs(w_[a]);
        ambOffset_[a] = wa * kMaxAmbiguousOffset <= std::abs(w_[N_])
                            ? kMaxAmbiguousOffset
                            : std::min(kMaxAmbiguousOffset, std::max(1, int(std::ceil(std::abs(w_[N_]) / wa))));
    }
    sixteen_ = traversalIsa() == Isa::Avx512;
    hasNormal_ = n_.x != 0.f || n_.y != 0.f || n_.z != 0.f;
    tangentOffset_ = 0.5f * (std::abs(n_.x) + std::abs(n_.y) + std::abs(n_.z));

    // The mask covers every point of every met voxel (|u| ≤ r_U + 1 + (r_N + 1)|k_U|) plus the
    // bilinear neighbours.
    halfU_ = int(std::ceil(r_[U_] + 1.f + (r_[N_] + 1.f) * std::abs(kU_))) + 2;
    halfV_ = int(std::ceil(r_[V_] + 1.f + (r_[N_] + 1.f) * std::abs(kV_))) + 2;
    sizeU_ = 2 * halfU_, sizeV_ = 2 * halfV_;
    const size_t cells = size_t(sizeU_) * size_t(sizeV_);
    if (s_.sweep.size() < cells) s_.sweep.resize(cells);
    // A row and a cell in front; one cell past the end for the wide path's four-byte reads.
    if (s_.shadowable.size() < cells + size_t(sizeU_) + 2) s_.shadowable.resize(cells + size_t(sizeU_) + 2, kNoOccluder);
    shadow_ = s_.shadowable.data() + sizeU_ + 1;
    findValidRows();
    markInvalidCells();
#if defined(__SSE2__)
    for (int a = 0; a < 3; ++a) {
        four_.gridOrigin[a] = _mm_set1_ps(g_.origin[a]), four_.o[a] = _mm_set1_ps(o_[a]), four_.w[a] = _mm_set1_ps(w_[a]);
        four_.n[a] = _mm_set1_ps(n_[a]), four_.aU[a] = _mm_set1_ps(aU_[a]), four_.aV[a] = _mm_set1_ps(aV_[a]);
    }
    four_.invVoxel = _mm_set1_ps(invVoxel_), four_.length = _mm_set1_ps(L_), four_.kernel2 = _mm_set1_ps(kernel2_);
    for (int a = 0; a < 3; ++a) {
        four_.absW[a] = _mm_set1_ps(absW_[a]), four_.absN[a] = _mm_set1_ps(absN_[a]);
        four_.absAU[a] = _mm_set1_ps(absAU_[a]), four_.absAV[a] = _mm_set1_ps(absAV_[a]);
    }
    four_.halfU = _mm_set1_epi32(halfU_), four_.halfV = _mm_set1_epi32(halfV_);
#endif
    s_.occluders.clear();
    s_.samples.clear();
    s_.bricks.clear();
    const size_t slices = size_t(dimN_ + kMaxAmbiguousOffset);
    if (s_.sampleSlices.size() < slices) s_.sampleSlices.resize(slices, 0), s_.occluderSlices.resize(slices, 0);
}

// The shadowable map is all kNoOccluder between cylinders, the slice counts zero: clear what
// this one touched. (The sweep mask is written whole by the next one.)
CylinderTraversal::~CylinderTraversal() {
    clearShadowable();
    for (int i = sliceMin_; i <= sliceMax_; ++i) s_.sampleSlices[size_t(i)] = 0;
    for (int i = occluderMin_; i <= occluderMax_; ++i) s_.occluderSlices[size_t(i)] = 0;
}

// Cell (i, j), relative to the mask centre: its centre within h + margin of the axis line.
bool CylinderTraversal::validCell(int i, int j) const {
    Vec3 q(0.f);
    q[U_] = float(i) + 0.5f;
    q[V_] = float(j) + 0.5f;
    const float along = glm::dot(q, w_);
    return glm::dot(q, q) - along * along <= valid2_;
}

// The valid cells of each mask row j: [rows[j].lo, rows[j].hi] (mask indices, may reach past
// the mask; empty when lo > hi). Per row the cells' distance² to the axis is a convex
// quadratic in i (second difference 2(1 − ω_U²) ≥ 1, far above rounding), so the valid cells
// are contiguous; the bounds are estimated analytically, then settled with validCell itself so
// that they agree with it exactly.
void CylinderTraversal::findValidRows() {
    if (s_.rows.size() < size_t(sizeV_)) s_.rows.resize(size_t(sizeV_));
#if RS_TRAVERSE_AVX512
    if (sixteen_) return findValidRows16();
#endif
    for (int j = 0; j < sizeV_; ++j) s_.rows[size_t(j)] = findValidRow(j);
}

// Row j's valid cells, as findValidRows states it.
RowRange CylinderTraversal::findValidRow(int j) const {
    const float qa = 1.f - w_[U_] * w_[U_], qb = w_[U_] * w_[V_], qc = 1.f - w_[V_] * w_[V_];
    const int jj = j - halfV_;
    const float y = float(jj) + 0.5f;
    const float xc = rowMinimum(j);
    int ic = int(std::floor(xc));  // x = ic + ½ is the cell centre nearest the minimum
    if (!validCell(ic, jj)) {
        if (validCell(ic - 1, jj)) --ic;
        else if (validCell(ic + 1, jj)) ++ic;
        else return {INT_MAX / 2, INT_MIN / 2};
    }
    const float disc = std::max(0.f, qb * qb * y * y - qa * (qc * y * y - valid2_));
    const float half = std::sqrt(disc) / qa;
    int lo = std::min(ic, int(std::floor(xc - half - 0.5f)) + 1);
    int hi = std::max(ic, int(std::floor(xc + half - 0.5f)));
    while (lo < ic && !validCell(lo, jj)) ++lo;
    while (validCell(lo - 1, jj)) --lo;
    while (hi > ic && !validCell(hi, jj)) --hi;
    while (validCell(hi + 1, jj)) ++hi;
    return {lo + halfU_, hi + halfU_};
}

// The sweep mask for this cylinder: 0 in the valid cells, kInvalidCell in the others (which
// no occluder is added to), so that the sixteen-lane steps read a cell's validity with its value
// instead of gathering its row's range.
void CylinderTraversal::markInvalidCells() {
    for (int j = 0; j < sizeV_; ++j) {
        float* row = &s_.sweep[size_t(sizeU_) * size_t(j)];
        const int lo = std::max(0, s_.rows[size_t(j)].lo), hi = std::min(sizeU_ - 1, s_.rows[size_t(j)].hi);
        std::fill(row, row + sizeU_, kInvalidCell);
        if (lo <= hi) std::fill(row + lo, row + hi + 1, 0.f);
    }
}

// -- Gathering occluders and samples (§5.1–5.3) ----------------------------------------------

// Both cache lines of a brick's payload, and the lines of its first sixteen voxels' counts
// (where the node says they start: reading the payload for it would wait for the payload).
inline void CylinderTraversal::prefetchBrick(Node node) const {
    const char* p = reinterpret_cast<const char*>(&tree_.bricks[node.brick()]);
    __builtin_prefetch(p);
    __builtin_prefetch(p + sizeof(Brick) - 1);
    const size_t first = node.voxelHint(), voxels = tree_.voxels.size();
    if (first >= voxels) return;  // no hint, or a brick without voxels at the end
    __builtin_prefetch(&tree_.voxels[first]);
    __builtin_prefetch(&tree_.voxels[std::min(first + 15, voxels - 1)]);
}

// From the root, the part of [0, L] whose disc boxes touch the grid, near child first. The
// leaves are worked on kLeafLag leaves after the walk meets them, in the same order, their
// payloads and voxel counts asked for when met: both are then in cache when gatherBrick reads
// them (read at once, half of gatherBrick's time was the wait for the payload's first line, and
// a third of the candidate step's the wait for the counts).
void CylinderTraversal::gather() {
    StackEntry e{0, 0.f, L_, {0, 0, 0}, {uint16_t(g_.dims.x), uint16_t(g_.dims.y), uint16_t(g_.dims.z)}};
    clipToBox(o_, w_, r_, Vec3(0.f), Vec3(g_.dims), e.t0, e.t1);
    s_.stack.clear();
    MetLeaf lag[kLeafLag];
    unsigned met = 0, done = 0;  // leaves met, leaves worked on
    // The near child is worked on next without going through the stack (a stored entry read
    // right back waits for the store); only far children are pushed.
    bool next = e.t0 <= e.t1;
    while (next || !s_.stack.empty()) {
        if (!next) {
            e = s_.stack.back();
            s_.stack.pop_back();
        }
        next = false;
        ++st_.nodes;
        const Node node = tree_.nodes[e.node];
        if (node.type() == NodeType::Split) {
            next = descend(e, node);
            continue;
        }
        if (node.type() == NodeType::Empty) continue;
        if (node.type() == NodeType::Brick) prefetchBrick(node);
        if (met - done == kLeafLag) gatherLeaf(lag[done++ % kLeafLag]);
        lag[met++ % kLeafLag] = {e, node};
    }
    while (done != met) gatherLeaf(lag[done++ % kLeafLag]);
}

// A met leaf's occluders (and, for a brick, whether its samples may be reached).
void CylinderTraversal::gatherLeaf(const MetLeaf& leaf) {
    if (leaf.node.type() == NodeType::Brick) gatherBrick(leaf.entry, leaf.node.brick());
    else gatherOcclusionBlock(leaf.entry, leaf.node);
}

// Shrink the cylinder bounds to each child: the far child goes on the stack, the near one
// replaces e (false when the cylinder misses it).
inline bool CylinderTraversal::descend(StackEntry& e, Node node) {
    const int a = node.axis();
    const float plane = float(node.plane());
    StackEntry lower = e, upper = e;
    lower.node = e.node + 1;
    lower.hi[a] = uint16_t(node.plane());
    clipUpperFace(o_[a], w_[a], r_[a], plane, lower.t0, lower.t1);
    upper.node = node.upperChild();
    upper.lo[a] = uint16_t(node.plane());
    clipLowerFace(o_[a], w_[a], r_[a], plane, upper.t0, upper.t1);
    const StackEntry& nearChild = w_[a] >= 0.f ? lower : upper;
    const StackEntry& farChild = w_[a] >= 0.f ? upper : lower;
    __builtin_prefetch(&tree_.nodes[upper.node]);
    if (farChild.t0 <= farChild.t1) s_.stack.push_back(farChild);
    if (!(nearChild.t0 <= nearChild.t1)) return false;
    e = nearChild;
    return true;
}

// Whether every voxel of `bits` (a brick's, min corner e.lo) lies behind the origin's tangent
// plane as inFrontOfTangent decides it, (centre − o)·n ≤ ½‖n‖₁: the box of their centres does, with
// a margin above the rounding, so that no voxel the per-voxel test would keep is skipped.
bool CylinderTraversal::allBehindTangent(const StackEntry& e, uint64_t bits) const {
    const uint64_t yx = bits | bits >> 16 | bits >> 32 | bits >> 48;  // 16 bits: x + 4y
    const unsigned xs = unsigned(yx | yx >> 4 | yx >> 8 | yx >> 12) & 15u;
    unsigned ys = 0, zs = 0;
    for (int k = 0; k < 4; ++k) {
        ys |= unsigned((yx >> (4 * k) & 15u) != 0) << k;
        zs |= unsigned((bits >> (16 * k) & 0xffffu) != 0) << k;
    }
    const unsigned axis[3] = {xs, ys, zs};
    float top = 0.f;
    for (int a = 0; a < 3; ++a) {
        const int lo = __builtin_ctz(axis[a]), hi = 31 - __builtin_clz(axis[a]);
        const float c = float(e.lo[a]) + 0.5f - o_[a];
        top += n_[a] * (n_[a] >= 0.f ? c + float(hi) : c + float(lo));  // the box corner farthest along n
    }
    return top <= tangentOffset_ - 1e-3f;
}

// The brick's occupied voxels that the cylinder meets become occluders, walked over the set
// bits (the rank of a bit among the occupied ones is where its counts are); a brick with
// samples the cylinder may reach (its sample box tested) is kept for visitSamples.
void CylinderTraversal::gatherBrick(const StackEntry& e, uint32_t index) {
    const Brick& brick = tree_.bricks[index];
    if (brick.sampleCount > 0) {
        Vec3 lo, hi;
        brick.sampleBounds(Vec3(e.lo[0], e.lo[1], e.lo[2]), lo, hi);
        if (boxMayBeReached(lo, hi)) s_.bricks.push_back({e, index});
    }
    // Only voxels with counts on a side ω sees can occlude (the others would add 0).
    const uint64_t candidates = brick.sides[side_[0]] | brick.sides[side_[1]] | brick.sides[side_[2]];
    // Most candidates lie on the surface the photon leaves, behind its tangent plane (85 % at
    // the paper's settings): all of a brick's at once when their box is, else one by one,
    // before the costlier met test.
    if (!candidates || (hasNormal_ && allBehindTangent(e, candidates))) return;
#if RS_TRAVERSE_AVX512
    if (sixteen_) return gatherBrickOccluders16(e, brick, candidates);
#endif
    auto voxel = [&](int bit) { return brickVoxel(brick, bit); };
#if defined(__SSE2__)
    const __m128i corner[3] = {_mm_set1_epi32(e.lo[0]), _mm_set1_epi32(e.lo[1]), _mm_set1_epi32(e.lo[2])};
    // Four candidates at a time: the tangent test and the sure met test in lanes, the same
    // operations in the same order as inFrontOfTangent and surelyMet (so the same answers),
    // the exact met test for the lanes left.
    for (uint64_t bits = candidates; bits;) {
        int bit[4], n = 0;
        for (; n < 4 && bits; ++n, bits &= bits - 1) bit[n] = __builtin_ctzll(bits);
        for (int k = n; k < 4; ++k) bit[k] = bit[0];
        // The voxels in lanes, made from the bit numbers in registers (scalar stores read back
        // as a vector would wait for each other).
        const __m128i b = _mm_setr_epi32(bit[0], bit[1], bit[2], bit[3]), three = _mm_set1_epi32(3);
        const __m128i vi[3] = {_mm_add_epi32(corner[0], _mm_and_si128(b, three)),
                               _mm_add_epi32(corner[1], _mm_and_si128(_mm_srli_epi32(b, 2), three)),
                               _mm_add_epi32(corner[2], _mm_srli_epi32(b, 4))};
        alignas(16) int v[3][4];
        __m128 d[3];
        for (int a = 0; a < 3; ++a) {
            _mm_store_si128(reinterpret_cast<__m128i*>(v[a]), vi[a]);
            d[a] = _mm_sub_ps(_mm_add_ps(_mm_cvtepi32_ps(vi[a]), _mm_set1_ps(0.5f)), four_.o[a]);
        }
        const __m128 along = dot4(four_.w, d[0], d[1], d[2]);
        const __m128 dd = dot4(d, d[0], d[1], d[2]);
        const __m128 sure = _mm_and_ps(_mm_and_ps(_mm_cmpge_ps(along, _mm_setzero_ps()), _mm_cmple_ps(along, four_.length)),
                                       _mm_cmplt_ps(_mm_sub_ps(dd, _mm_mul_ps(along, along)), _mm_set1_ps(hOcc_ * hOcc_)));
        const unsigned front = hasNormal_ ? unsigned(_mm_movemask_ps(_mm_cmpgt_ps(dot4(four_.n, d[0], d[1], d[2]),
                                                                                  _mm_set1_ps(tangentOffset_))))
                                          : 15u;
        const unsigned met = unsigned(_mm_movemask_ps(sure));
        if (!front) continue;
        // The centres' cells, projected as addOccluder projects one.
        alignas(16) int cu[4], cv[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(cu), _mm_add_epi32(floorToInt4(dot4(four_.aU, d[0], d[1], d[2])), four_.halfU));
        _mm_store_si128(reinterpret_cast<__m128i*>(cv), _mm_add_epi32(floorToInt4(dot4(four_.aV, d[0], d[1], d[2])), four_.halfV));
        for (int k = 0; k < n; ++k) {
            if (!(front >> k & 1u)) continue;
            if (invalidCell(cu[k], cv[k])) continue;  // before the exact met test
            if (met >> k & 1u || voxelMet(v[0][k], v[1][k], v[2][k])) addOccluderAt(cu[k], cv[k], v[N_][k], voxel(bit[k]));
        }
    }
#else
    for (uint64_t bits = candidates; bits; bits &= bits - 1) {
        const int bit = __builtin_ctzll(bits);
        const int x = e.lo[0] + (bit & 3), y = e.lo[1] + ((bit >> 2) & 3), z = e.lo[2] + (bit >> 4);
        const Vec3 c(float(x) + 0.5f, float(y) + 0.5f, float(z) + 0.5f);
        if (inFrontOfTangent(c) && (surelyMet(c) || voxelMet(x, y, z))) addOccluder(x, y, z, voxel(bit));
    }
#endif
}


// A single Occlusion voxel, or a collapsed block: each of its met voxels is an occluder.
void CylinderTraversal::gatherOcclusionBlock(const StackEntry& e, Node node) {
    auto centre = [](int x, int y, int z) { return Vec3(float(x) + 0.5f, float(y) + 0.5f, float(z) + 0.5f); };
    if (e.hi[0] - e.lo[0] == 1 && e.hi[1] - e.lo[1] == 1 && e.hi[2] - e.lo[2] == 1) {
        if (inFrontOfTangent(centre(e.lo[0], e.lo[1], e.lo[2]))) addOccluder(e.lo[0], e.lo[1], e.lo[2], node.voxel());
        return;
    }
    int i0[3], i1[3];
    metRange(e, i0, i1);
    for (int z = i0[2]; z < i1[2]; ++z)
        for (int y = i0[1]; y < i1[1]; ++y)
            for (int x = i0[0]; x < i1[0]; ++x)
                if (inFrontOfTangent(centre(x, y, z)) && voxelMet(x, y, z)) addOccluder(x, y, z, node.voxel());
}

// An occupied, met voxel strictly in front of the origin's tangent plane (the callers test
// both, the cheaper plane first) adds its occlusion along ω to the cell of its centre's
// projection, in its (ambiguity-offset) slice.
void CylinderTraversal::addOccluder(int ix, int iy, int iz, VoxelOcclusion voxel) {
    // The centre's projection (u, v) = ((c − o)·aU, (c − o)·aV): the same value as
    // (c_U − o_U) − k_U (c_N − o_N), the other terms being exact zeros and ones.
    const Vec3 d = Vec3(float(ix) + 0.5f, float(iy) + 0.5f, float(iz) + 0.5f) - o_;
    const int v[3] = {ix, iy, iz};
    const int cu = floorToInt(glm::dot(d, aU_)) + halfU_, cv = floorToInt(glm::dot(d, aV_)) + halfV_;
    if (!invalidCell(cu, cv)) addOccluderAt(cu, cv, v[N_], voxel);
}

// The occluder of voxel layer `layer` along N, its centre projecting into mask cell (cu, cv),
// which invalidCell has let through.
void CylinderTraversal::addOccluderAt(int cu, int cv, int layer, VoxelOcclusion voxel) {
    float occ = 0.f;
    for (int a = 0; a < 3; ++a) occ += occWeight_[a] * float(voxel.count(side_[a]));
    occ = std::min(1.f, occ);
    if (occ <= 0.f) return;
    const int slice = sliceOf(layer) + (voxel.ambiguous() ? ambOffset_[voxel.dominantAxis()] : 0);
    // Inside the mask by construction (the mask covers the cylinder's cross-section and the
    // margin); a release build still never writes past it.
    RS_DCHECK(cu >= 0 && cv >= 0 && cu < sizeU_ && cv < sizeV_);
    if (cu < 0 || cv < 0 || cu >= sizeU_ || cv >= sizeV_) return;
    // Written field by field where it lies: an event made on the stack and copied was read back
    // as one 8-byte word over two 4-byte stores, which the CPU cannot forward (a third of the
    // function's time).
    OccluderEvent& ev = s_.occluders.emplace_back();
    ev.cell = cu + sizeU_ * cv, ev.slice = slice, ev.occ = occ;
    ++s_.occluderSlices[size_t(slice)];
    occluderMin_ = std::min(occluderMin_, slice), occluderMax_ = std::max(occluderMax_, slice);
    ++st_.occluders;
}

// Bounds of the cylinder part in a node: its t-range's disc boxes, clipped to the node.
void CylinderTraversal::nodeBounds(const StackEntry& e, Vec3& lo, Vec3& hi) const {
    for (int b = 0; b < 3; ++b) {
        const float a0 = o_[b] + e.t0 * w_[b], a1 = o_[b] + e.t1 * w_[b];
        lo[b] = std::max(float(e.lo[b]), std::min(a0, a1) - r_[b]);
        hi[b] = std::min(float(e.hi[b]), std::max(a0, a1) + r_[b]);
    }
}

// The voxels of a node's box that may be met: the cylinder part's bounds, widened a voxel.
void CylinderTraversal::metRange(const StackEntry& e, int i0[3], int i1[3]) const {
    Vec3 lo, hi;
    nodeBounds(e, lo, hi);
    for (int b = 0; b < 3; ++b) {
        i0[b] = std::max(int(e.lo[b]), floorToInt(lo[b]) - 1);
        i1[b] = std::min(int(e.hi[b]), ceilToInt(hi[b]) + 1);
    }
}

// A point within h' of the axis at a depth t ∈ [0, L] lies in that t's disc, whose box then
// overlaps its voxel's: the voxel is met without the six divisions.
bool CylinderTraversal::surelyMet(const Vec3& p) const {
    const Vec3 d = p - o_;
    const float along = glm::dot(d, w_);
    return along >= 0.f && along <= L_ && glm::dot(d, d) - along * along < hOcc_ * hOcc_;
}

// A voxel is met when the t-range its own six faces allow is not empty (the same range, bit
// for bit, as the one the splits narrowed down to its leaf).
bool CylinderTraversal::voxelMet(int x, int y, int z) const {
    float t0 = 0.f, t1 = L_;
    const Vec3 lo{float(x), float(y), float(z)};
    clipToBox(o_, w_, r_, lo, lo + 1.f, t0, t1);
    return t0 <= t1;
}

}  // namespace rs
