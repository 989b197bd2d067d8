// Traversal of a photon cylinder through the occlusion tree (paper §5.1–5.3, docs/design.md §8).
//
// Takes:   the OcclusionTree, the (tree-sorted) EyeSamples, a Cylinder in voxel space, a
//          per-thread TraversalScratch and a visitor visit(uint32_t sample, float V).
// Calls:   visit(i, V) once for every eye sample i the cylinder reaches whose visibility
//          V = 1 − occlusion is > 0, in no particular order. The splat stage does its own
//          kernel weight and normal tests; samples with V = 0 are not handed over. A visitor
//          that can also be called as visit(const uint32_t* index, size_t count) gets the
//          samples with V = 1 that way, a brick's at a time; one that can be called as
//          visit(const uint32_t* index, const float* V, size_t count) gets the others that
//          way, up to sixteen at a time.
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
//    cell centre is within √2/2 of it, so it always has a valid neighbour. No sample reads an
//    invalid cell, so the voxels of invalid cells are not kept as occluders (a third of the
//    met ones at the paper's settings), and are dropped before the exact met test.
//  • V = 1 − bilinear interpolation of those capped cell values between the 4 cell centres
//    nearest to the sample's (u, v), over the valid ones, the weights renormalised. Without
//    the validity rule a sample near the rim would read half-empty cells outside the
//    cylinder and light would leak through walls at small h.
// The definition does not depend on the kd order: the traversal collects the met
// occluders and reached samples (CylinderTraversal::gather), then sweeps them slice by slice
// (sweep); a sample none of whose four cells holds an occluder of an earlier slice reads V = 1
// at once. The kd order is near to far (lower child first iff ω_a ≥ 0); nothing depends on it.
// Cylinder parts outside the grid or past L are
// never visited. At a brick leaf the occupied voxels (its mask's
// bits inside the cylinder part's bounds) that are met become occluders and its samples that
// are reached are collected (octants of the brick out of the cylinder's reach are skipped
// whole); a collapsed Occlusion block contributes each of its met voxels.
#pragma once

#include <climits>
#include <memory>
#include <type_traits>
#include <utility>
#include <cmath>
#include <cstdint>
#include <vector>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "core/error.h"
#include "core/simd.h"
#include "occlusion/eye_samples.h"
#include "occlusion/kdtree.h"

// The reach test, a brick's candidate occluders and the sweep's reads have sixteen-lane AVX-512
// paths (kdtree_traverse_avx512.cpp), used where core/simd.h's traversalIsa() is Avx512.

namespace rs {

struct Cylinder {
    Vec3 origin{0.f};        // o, voxel space
    Vec3 dir{0.f, 0.f, 1.f};  // ω, unit
    float radius = 1.f;       // h, voxels
    float length = 0.f;       // L, voxels
    Vec3 originNormal{0.f};   // n_o, unit normal of the surface the photon leaves; zero if none
};

// Tested: samples whose position was read to test whether they are reached. Swept: reached
// samples an occluder may shadow, read in the slice sweep. Boxed: reached samples taken a box
// at a time, their positions not read.
#define RS_TRAVERSAL_COUNTERS(X)                                                                  \
    X(cylinders, "traversal_cylinders") X(nodes, "traversal_nodes") X(occluders, "traversal_occluders") \
    X(samplesReached, "traversal_samples_reached") X(samplesVisited, "traversal_samples_visited")     \
    X(samplesTested, "traversal_samples_tested") X(samplesSwept, "traversal_samples_swept")           \
    X(samplesBoxed, "traversal_samples_boxed")
struct TraversalStats {
    RS_TRAVERSAL_COUNTERS(RS_COUNTER_MEMBER)
    void add(const TraversalStats& o) { RS_TRAVERSAL_COUNTERS(RS_COUNTER_ADD) }
    void report(Stats& stats) const { RS_TRAVERSAL_COUNTERS(RS_COUNTER_REPORT) }
};

constexpr int kMaxAmbiguousOffset = 4;    // N slices
constexpr float kOccluderMargin = 0.6f;   // h' = h + margin gathers the occluders of valid cells
constexpr float kValidCellMargin = 0.71f; // valid cells: centre within h + margin of the axis
constexpr float kBoxReachSlack = 0.01f;   // voxels: a box of samples is tested that much wider
// A box surely unshadowed: its bounds narrowed by kSureSlack + kSureSlackPerSize·size on depths,
// heights and projections, and by kSureSlack2PerSize2·size² on squared distances (size: the
// box's distance from the origin plus its half-diagonal plus 1), far above the per-sample tests'
// rounding. Shared by the one-box test and its four- and eight-lane forms, which must agree.
constexpr float kSureSlack = 0.01f, kSureSlackPerSize = 1e-5f, kSureSlack2PerSize2 = 4e-5f;
constexpr float kOctantEdge = 1e-3f;      // voxels: a brick's octant faces, widened past the positions' rounding
constexpr uint16_t kNoOccluder = 0xffff;  // the shadowable map's "no occluder in this block"
constexpr float kInvalidCell = -1.f;      // the sweep mask's value in a cell that is not valid
constexpr size_t kEventSlack = 16;         // sample lists: room past the last entry, for sixteen-lane stores

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
struct MetBrick {  // a brick leaf the cylinder meets, with its part of the cylinder
    StackEntry entry;
    uint32_t brick;
};
struct RowRange {  // a mask row's valid cells, [lo, hi]
    int32_t lo, hi;
};

inline int majorAxis(const Vec3& w) {
    int n = 0;
    for (int a = 1; a < 3; ++a)
        if (std::abs(w[a]) > std::abs(w[n])) n = a;
    return n;
}

}  // namespace kd_detail

// std::allocator, but a resize leaves the new elements default-initialised (for the events:
// not zeroed), as they are written right after.
template <class T>
struct UninitializedAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
        using other = UninitializedAllocator<U>;
    };
    UninitializedAllocator() = default;
    template <class U>
    UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
    template <class U>
    void construct(U* p) noexcept {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};
template <class T>
using EventVector = std::vector<T, UninitializedAllocator<T>>;

// Asks for the cache lines of elements [first, last) of a per-sample array: the tree's samples
// are reached from all over the arrays, and waiting for them was the traversal's largest cost.
// Always inlined: GCC drops calls to a function whose only effects are prefetches.
template <class T>
__attribute__((always_inline)) inline void prefetchRange(const std::vector<T>& v, uint32_t first, uint32_t last) {
    const char* end = reinterpret_cast<const char*>(v.data() + last);
    for (const char* q = reinterpret_cast<const char*>(v.data() + first); q < end; q += 64) __builtin_prefetch(q);
}

// A visitor of several callables (one per kind of call, as std::visit's examples build it).
template <class... Fns>
struct Overloaded : Fns... {
    using Fns::operator()...;
};
template <class... Fns>
Overloaded(Fns...) -> Overloaded<Fns...>;

// Per-thread scratch: the stack, the mask and the event lists grow to the largest cylinder
// seen and are reused, so traversal allocates nothing in steady state.
class TraversalScratch {
public:
    std::vector<kd_detail::StackEntry> stack;
    std::vector<float> sweep;  // the mask's cells: occlusion summed so far, kInvalidCell where not valid
    // Per mask cell (a row and a cell in front): the first slice of an occluder in one of the 2×2
    // cells from it on (kNoOccluder: none).
    std::vector<uint16_t> shadowable;
    std::vector<kd_detail::MetBrick> bricks;  // the met bricks that hold samples, in kd order
    EventVector<kd_detail::OccluderEvent> occluders, occludersSorted;
    EventVector<kd_detail::SampleEvent> samples, samplesSorted;
    EventVector<uint32_t> unshadowed;  // one brick's reached samples that no occluder before their slice can shadow
    // Per slice: how many sample and occluder events this cylinder has there (zero between
    // cylinders), counted as they are made, for the sweep's counting sort.
    std::vector<uint32_t> sampleSlices, occluderSlices;
    std::vector<kd_detail::RowRange> rows;  // the valid cells of each mask row
};

// One cylinder's traversal, in the paper's steps: the mask is set up by the constructor
// (§5.1); gather() walks the tree near to far and collects the met occluders and the met
// bricks that hold samples (§5.1–5.3); visitSamples() reaches the samples of those bricks and
// hands over at once, while the brick's arrays are in cache, the ones that read V = 1 (none of
// their bilinear cells holds an occluder of an earlier slice: 91 % of them at the paper's
// settings on the glossy box) — a brick's or an octant's at once, positions unread, when the box
// its samples lie in is surely reached and holds no occluder's block at all (59 % of them there);
// sweep() reads the others' visibility slice by slice (§5.1).
class CylinderTraversal {
public:
    CylinderTraversal(const OcclusionTree& tree, const EyeSamples& eye, const Cylinder& cyl, TraversalScratch& s);
    ~CylinderTraversal();

    void gather();
    template <class Visit>
    void visitSamples(Visit&& visit);
    template <class Visit>
    void sweep(Visit&& visit);
    const TraversalStats& stats() const { return st_; }

private:
    using StackEntry = kd_detail::StackEntry;
    using SampleEvent = kd_detail::SampleEvent;
    using RowRange = kd_detail::RowRange;

    // Mask set-up.
    void findValidRows();
    kd_detail::RowRange findValidRow(int j) const;
    // Where row j's distances² to the axis, Q(x) = qa x² − 2 qb x y + qc y² (x = i + ½, y = j + ½,
    // relative to the mask centre), are least: x = qb y / qa.
    float rowMinimum(int j) const {
        const float qa = 1.f - w_[U_] * w_[U_], qb = w_[U_] * w_[V_];
        return qb * (float(j - halfV_) + 0.5f) / qa;
    }
#if RS_TRAVERSE_AVX512
    void findValidRows16();
#endif
    void markInvalidCells();
    bool validCell(int i, int j) const;  // relative to the mask centre
    bool validMaskCell(int i, int j) const { return i >= s_.rows[size_t(j)].lo && i <= s_.rows[size_t(j)].hi; }
    // A cell of the mask that is not valid: no sample reads it, so a voxel projecting there is no
    // occluder. (One outside the mask is left to addOccluderAt, which counts it.)
    bool invalidCell(int cu, int cv) const {
        return unsigned(cu) < unsigned(sizeU_) && unsigned(cv) < unsigned(sizeV_) && !validMaskCell(cu, cv);
    }
    int sliceOf(int vN) const { return forward_ ? vN : dimN_ - 1 - vN; }

    // Gathering.
    // Inlined into the walk, so that the entry it narrows need not go through memory for a call.
    __attribute__((always_inline)) bool descend(StackEntry& e, Node node);
    struct MetLeaf {
        StackEntry entry;
        Node node;
    };
    static constexpr unsigned kLeafLag = 8;  // leaves met before the first is worked on
    // A met brick's payload and voxel counts; a kept brick's sample positions. Always inlined:
    // GCC takes a function whose only effects are prefetches for one without effects, and drops
    // the calls to it when it is not inlined early.
    __attribute__((always_inline)) void prefetchBrick(Node node) const;
    __attribute__((always_inline)) void prefetchPositions(const kd_detail::MetBrick& met) const {
        const Brick& brick = tree_.bricks[met.brick];
        prefetchRange(eye_.position, brick.firstSample, brick.firstSample + brick.sampleCount);
    }
    void gatherLeaf(const MetLeaf& leaf);
    void gatherBrick(const StackEntry& e, uint32_t index);
#if RS_TRAVERSE_AVX512
    void gatherBrickOccluders16(const StackEntry& e, const Brick& brick, uint64_t candidates);
    // Sixteen candidate occluders in AVX-512 registers: defined, with the step that adds them, in
    // kdtree_traverse_avx512.cpp, so that no sixteen-lane type reaches this header.
    struct Occluders16;
    size_t addOccluders16(const Occluders16& c, size_t n);
#endif
    void gatherOcclusionBlock(const StackEntry& e, Node node);
    // The counts of a brick's voxel: the rank of its bit among the occupied ones is where they are.
    VoxelOcclusion brickVoxel(const Brick& brick, int bit) const {
        return tree_.voxels[brick.firstVoxel + uint32_t(bitCount(brick.occupied & ((uint64_t(1) << bit) - 1)))];
    }
    // An occluder's voxel centre must lie strictly in front of the origin's tangent plane
    // (§5.2), past half the normal's L1 norm: the whole voxel box does.
    bool inFrontOfTangent(const Vec3& centre) const { return !hasNormal_ || glm::dot(centre - o_, n_) > tangentOffset_; }
    void addOccluder(int ix, int iy, int iz, VoxelOcclusion voxel);
    void addOccluderAt(int cu, int cv, int layer, VoxelOcclusion voxel);
    bool allBehindTangent(const StackEntry& e, uint64_t bits) const;
    void nodeBounds(const StackEntry& e, Vec3& lo, Vec3& hi) const;
    void metRange(const StackEntry& e, int i0[3], int i1[3]) const;
    bool surelyMet(const Vec3& p) const;
    bool voxelMet(int x, int y, int z) const;

    // Reaching the samples.
    void markShadowable();
    void clearShadowable();
    void gatherBrickSamples(const kd_detail::MetBrick& met);
    struct Reach {  // a reached sample: its (u, v), first bilinear cell and voxel layer along N
        float u, v;
        int i0, j0, voxelN;
    };
    struct Reach4 {
        alignas(16) float u[4], v[4];
        alignas(16) int i0[4], j0[4], voxelN[4];
    };
    template <class TakeAll>
    void gatherOctants(const kd_detail::MetBrick& met, const Vec3& lo, const Vec3& hi, TakeAll& takeAll, size_t& n, size_t& listed);
    void gatherSampleRange(const StackEntry& e, uint32_t first, uint32_t last, bool surelyReached, size_t& events, size_t& listed);
#if RS_TRAVERSE_AVX512
    void gatherSampleRange16(const StackEntry& e, uint32_t first, uint32_t last, bool surelyReached, size_t& events, size_t& listed);
#endif
    void gatherSampleScalar(const StackEntry& e, uint32_t first, uint32_t last, size_t& events, size_t& listed, int& sliceMin,
                            int& sliceMax);
    void addReached(uint32_t i, const Reach& r, int layerLo, int layerHi, size_t& events, size_t& listed, int& sliceMin,
                    int& sliceMax);
    bool reach(const Vec3& world, Reach& r) const;
    template <bool kTest>
    uint32_t reach4(const Vec3* world, Reach4& r) const;
    bool boxMayBeReached(const Vec3& lo, const Vec3& hi) const;
    bool boxSurelyUnshadowed(const Vec3& lo, const Vec3& hi) const;
    bool rectUnshadowed(int i0, int i1, int j0, int j1) const;
#if defined(__SSE2__)
    void boxTests4(const __m128 lo[3], const __m128 hi[3], uint32_t& may, uint32_t& sure, int32_t rect[4][4]) const;
#endif
#if RS_TRAVERSE_AVX512
    void boxTests8(const Vec3& corner, const Vec3& lo, const Vec3& hi, uint32_t& may, uint32_t& sure, int32_t rect[2][4][4]) const;
#endif
    int firstShadowingSlice(int i0, int j0) const;

    // Sweep.
    void prepareSweep();
    float read(const SampleEvent& ev) const;
    void read4(const SampleEvent* ev, float vis[4]) const;
#if RS_TRAVERSE_AVX512
    int read16(const SampleEvent* ev, int count, uint32_t index[16], float vis[16]) const;
#endif
    template <class Visit>
    void handOver(Visit& visit, const uint32_t* index, const float* vis, int count);

    const OcclusionTree& tree_;
    const EyeSamples& eye_;
    const GridGeometry& g_;
    TraversalScratch& s_;
    TraversalStats st_;
    Vec3 o_, w_, n_;
    Vec3 aU_, aV_;  // u = (p − o)·aU, v = (p − o)·aV
    Vec3 absW_, absN_, absAU_, absAV_;  // their components' magnitudes, for the box tests
    float L_, radius_, invVoxel_, hOcc_, kernel2_, valid2_, kU_, kV_, tangentOffset_;
    float r_[3], occWeight_[3];
    int N_, U_, V_, dimN_, halfU_, halfV_, sizeU_, sizeV_;
    int side_[3], ambOffset_[3];
    bool forward_, hasNormal_;
    bool sixteen_;  // traversalIsa() is Avx512, read once a cylinder: the sixteen-lane steps
    uint16_t* shadow_;  // the shadowable map's cell (0, 0)
    int sliceMin_ = INT_MAX, sliceMax_ = INT_MIN;  // the sample events' slices
    int occluderMin_ = INT_MAX, occluderMax_ = INT_MIN;  // the occluder events'
#if defined(__SSE2__)
    struct FourLanes {  // reach4's numbers, each in all four lanes, set once a cylinder
        __m128 gridOrigin[3], o[3], w[3], n[3], aU[3], aV[3], absW[3], absN[3], absAU[3], absAV[3], invVoxel, length, kernel2;
        __m128i halfU, halfV;
    } four_;
#endif
};

// V = 1 − the bilinear interpolation of the capped cell values between the 4 cell centres
// nearest to the sample's (u, v), over the valid ones, the weights renormalised.
inline float CylinderTraversal::read(const SampleEvent& ev) const {
    float x = ev.u - 0.5f, y = ev.v - 0.5f;
    const int ix = floorToInt(x), iy = floorToInt(y);
    int i0 = ix + halfU_, j0 = iy + halfV_;
    float fx = x - float(ix), fy = y - float(iy);
    // Valid cells only; num ≤ den term by term, so occ ≤ 1 and four full cells give exactly 1.
    float num = 0.f, den = 0.f;
    if (unsigned(i0) < unsigned(sizeU_ - 1) && unsigned(j0) < unsigned(sizeV_ - 1)) {
        // The whole block inside the mask (every reached sample's, by the mask's size).
        const float* row0 = &s_.sweep[size_t(i0) + size_t(sizeU_) * size_t(j0)];
        const float* row1 = row0 + sizeU_;
#if defined(__SSE2__)
        // The four cells in lanes (i0, j0), (i0 + 1, j0), (i0, j0 + 1), (i0 + 1, j0 + 1); an
        // invalid cell's weight made 0. Both sums are added in the same order, so num ≤ den.
        const __m128 value = _mm_min_ps(_mm_set1_ps(1.f),
                                        _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(row0)),
                                                     reinterpret_cast<const __m64*>(row1)));
        const __m128i range = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&s_.rows[size_t(j0)]));  // lo0 hi0 lo1 hi1
        const __m128i lo = _mm_shuffle_epi32(range, _MM_SHUFFLE(2, 2, 0, 0)), hi = _mm_shuffle_epi32(range, _MM_SHUFFLE(3, 3, 1, 1));
        const __m128i cell = _mm_add_epi32(_mm_set1_epi32(i0), _mm_setr_epi32(0, 1, 0, 1));
        const __m128 invalid = _mm_castsi128_ps(_mm_or_si128(_mm_cmplt_epi32(cell, lo), _mm_cmpgt_epi32(cell, hi)));
        const __m128 wx = _mm_add_ps(_mm_setr_ps(1.f, 0.f, 1.f, 0.f), _mm_mul_ps(_mm_setr_ps(-1.f, 1.f, -1.f, 1.f), _mm_set1_ps(fx)));
        const __m128 wy = _mm_add_ps(_mm_setr_ps(1.f, 1.f, 0.f, 0.f), _mm_mul_ps(_mm_setr_ps(-1.f, -1.f, 1.f, 1.f), _mm_set1_ps(fy)));
        const __m128 weight = _mm_andnot_ps(invalid, _mm_mul_ps(wx, wy));
        const __m128 term = _mm_mul_ps(weight, value);
        // (t0 + t2) + (t1 + t3) and the same for the weights.
        const __m128 pairs = _mm_add_ps(_mm_shuffle_ps(term, weight, _MM_SHUFFLE(1, 0, 1, 0)),
                                        _mm_shuffle_ps(term, weight, _MM_SHUFFLE(3, 2, 3, 2)));
        const __m128 sums = _mm_add_ps(pairs, _mm_shuffle_ps(pairs, pairs, _MM_SHUFFLE(2, 3, 0, 1)));
        num = _mm_cvtss_f32(sums), den = _mm_cvtss_f32(_mm_movehl_ps(sums, sums));
#else
        // Each row's valid range read once, and a skipped cell's weight made 0 instead of
        // branching (adding 0 leaves num and den as they were).
        const RowRange r0 = s_.rows[size_t(j0)], r1 = s_.rows[size_t(j0) + 1];
        auto add = [&](bool valid, float weight, float value) {
            weight = valid && weight > 0.f ? weight : 0.f;
            num += weight * std::min(1.f, value);
            den += weight;
        };
        add(i0 >= r0.lo && i0 <= r0.hi, (1.f - fx) * (1.f - fy), row0[0]);
        add(i0 + 1 >= r0.lo && i0 + 1 <= r0.hi, fx * (1.f - fy), row0[1]);
        add(i0 >= r1.lo && i0 <= r1.hi, (1.f - fx) * fy, row1[0]);
        add(i0 + 1 >= r1.lo && i0 + 1 <= r1.hi, fx * fy, row1[1]);
#endif
        return num > 0.f ? 1.f - num / den : 1.f;
    }
    auto cell = [&](int i, int j, float weight) {
        if (weight <= 0.f) return;
        if (j >= 0 && j < sizeV_ ? !validMaskCell(i, j) : !validCell(i - halfU_, j - halfV_)) return;
        float c = i < 0 || j < 0 || i >= sizeU_ || j >= sizeV_ ? 0.f : std::min(1.f, s_.sweep[size_t(i) + size_t(sizeU_) * j]);
        num += weight * c;
        den += weight;
    };
    cell(i0, j0, (1.f - fx) * (1.f - fy));
    cell(i0 + 1, j0, fx * (1.f - fy));
    cell(i0, j0 + 1, (1.f - fx) * fy);
    cell(i0 + 1, j0 + 1, fx * fy);
    return den > 0.f ? 1.f - num / den : 1.f;
}

// Brick by brick, in kd order: the reached samples that no occluder can shadow get V = 1 now;
// the others become events for the sweep.
template <class Visit>
void CylinderTraversal::visitSamples(Visit&& visit) {
    markShadowable();
    // A brick's positions are asked for two bricks ahead of reaching its samples (asked for when
    // the walk met the brick, many had left L1 by the time they were read).
    constexpr size_t kAhead = 2;
    for (size_t k = 0; k < std::min(kAhead, s_.bricks.size()); ++k) prefetchPositions(s_.bricks[k]);
    for (size_t k = 0; k < s_.bricks.size(); ++k) {
        if (k + kAhead < s_.bricks.size()) prefetchPositions(s_.bricks[k + kAhead]);
        const kd_detail::MetBrick& met = s_.bricks[k];
        gatherBrickSamples(met);
        if constexpr (std::is_invocable_v<Visit&, const uint32_t*, size_t>)
            visit(static_cast<const uint32_t*>(s_.unshadowed.data()), s_.unshadowed.size());
        else
            for (uint32_t i : s_.unshadowed) visit(i, 1.f);
        st_.samplesVisited += s_.unshadowed.size();
    }
}

// Slice by slice, a slice's samples read the mask before its occluders enter it.
template <class Visit>
void CylinderTraversal::sweep(Visit&& visit) {
    prepareSweep();
    size_t is = 0, io = 0;
    const EventVector<SampleEvent>& samples = s_.samplesSorted;
    const EventVector<kd_detail::OccluderEvent>& occluders = s_.occludersSorted;
    for (int slice = sliceMin_; is < samples.size(); ++slice) {
        const size_t end = s_.sampleSlices[size_t(slice)];  // the sort left each slice's end there
#if RS_TRAVERSE_AVX512
        if (sixteen_)
            while (is < end) {
                const int count = int(std::min<size_t>(16, end - is));
                alignas(64) uint32_t index[16];
                alignas(64) float vis[16];
                handOver(visit, index, vis, read16(&samples[is], count, index, vis));
                is += size_t(count);
            }
#endif
#if defined(__SSE2__)
        for (; is + 4 <= end; is += 4) {
            alignas(16) float vis[4];
            read4(&samples[is], vis);
            uint32_t index[4];
            float seen[4];
            int lit = 0;
            for (int k = 0; k < 4; ++k)
                if (vis[k] > 0.f) index[lit] = samples[is + size_t(k)].index, seen[lit++] = vis[k];
            handOver(visit, index, seen, lit);
        }
#endif
        for (; is < end; ++is) {
            const float vis = read(samples[is]);
            if (vis > 0.f) handOver(visit, &samples[is].index, &vis, 1);
        }
        for (; io < occluders.size() && occluders[io].slice == slice; ++io) s_.sweep[size_t(occluders[io].cell)] += occluders[io].occ;
    }
}

// The samples of one read that see light (V > 0), handed over as a list when the visitor takes
// lists, else one by one.
template <class Visit>
void CylinderTraversal::handOver(Visit& visit, const uint32_t* index, const float* vis, int count) {
    if constexpr (std::is_invocable_v<Visit&, const uint32_t*, const float*, size_t>) {
        if (count > 0) visit(index, vis, size_t(count));
    } else {
        for (int k = 0; k < count; ++k) visit(index[k], vis[k]);
    }
    st_.samplesVisited += uint64_t(count);
}

template <class Visit>
void traverseCylinder(const OcclusionTree& tree, const EyeSamples& eye, const Cylinder& cyl, TraversalScratch& s,
                      Visit&& visit, TraversalStats* statsOut = nullptr) {
    CylinderTraversal traversal(tree, eye, cyl, s);
    traversal.gather();
    traversal.visitSamples(visit);
    traversal.sweep(visit);
    if (statsOut) statsOut->add(traversal.stats());
}

}  // namespace rs
