// The steps of CylinderTraversal that reach the samples and sweep the slices
// (kdtree_traverse.h states the rules they implement); the mask set-up and the gathering of
// occluders are in kdtree_traverse.cpp.
#include "occlusion/kdtree_traverse.h"

#include <numeric>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace rs {

using namespace kd_detail;
// -- Reaching the samples (§5.1) --------------------------------------------------------------

// Marks each cell (i0, j0) whose 2×2 bilinear block (i0…i0+1, j0…j0+1) holds an occluder's
// cell with the first slice of those occluders: a sample in slice s whose block starts there
// reads only occluders of slices < s, so it reads 0, V = 1, when s is at most that first slice.
// The map has a row and a cell in front (shadow_ is past them), so the four cells are written
// without tests: for an occluder in column 0, the "cell to the left" is the previous row's last
// one, a mask edge no reached sample's block starts at (at worst a sample there would be swept,
// to the same V). A slice past the map's range is marked as the largest one it holds, a slice
// no later than the occluder's: a sample may be swept that needs not be, never the other way.
void CylinderTraversal::markShadowable() {
    for (const OccluderEvent& ev : s_.occluders) {
        uint16_t* row = shadow_ + ev.cell;
        const uint16_t slice = uint16_t(std::min(ev.slice, int32_t(kNoOccluder) - 1));
        for (uint16_t* c : {row, row - 1, row - sizeU_, row - sizeU_ - 1}) *c = std::min(*c, slice);
    }
}

// The map all kNoOccluder again, for the next cylinder.
void CylinderTraversal::clearShadowable() {
    for (const OccluderEvent& ev : s_.occluders) {
        uint16_t* row = shadow_ + ev.cell;
        row[0] = row[-1] = row[-sizeU_] = row[-sizeU_ - 1] = kNoOccluder;
    }
}

// The first slice of an occluder in the bilinear block that starts at mask cell (i0, j0)
// (kNoOccluder: none, or one past the map's range): a sample in a slice up to it reads V = 1.
inline int CylinderTraversal::firstShadowingSlice(int i0, int j0) const {
    if (unsigned(i0) < unsigned(sizeU_) && unsigned(j0) < unsigned(sizeV_)) return shadow_[size_t(i0) + size_t(sizeU_) * size_t(j0)];
    // A block at the mask's edge (none is, by the mask's size): cells outside hold nothing.
    int first = kNoOccluder;
    for (const OccluderEvent& ev : s_.occluders) {
        const int cu = ev.cell % sizeU_, cv = ev.cell / sizeU_;
        if ((cu == i0 || cu == i0 + 1) && (cv == j0 || cv == j0 + 1)) first = std::min(first, std::min(ev.slice, kNoOccluder - 1));
    }
    return first;
}

// A met brick's samples, by octant: each octant's part of the box its samples lie in is tested
// first (boxMayBeReached; gatherBrick tested the whole box), so that what the cylinder cannot
// reach is not read. A box whose samples are all surely reached and unshadowed
// (boxSurelyUnshadowed), an octant's (the whole brick's when it is not divided), goes to the
// unshadowed list without its positions being read: the list is the same, in the same order,
// as when each sample is tested. (A test of the whole divided brick first rarely passed and
// cost more than it saved.)
void CylinderTraversal::gatherBrickSamples(const MetBrick& met) {
    const Brick& brick = tree_.bricks[met.brick];
    const Vec3 corner(met.entry.lo[0], met.entry.lo[1], met.entry.lo[2]);
    Vec3 lo, hi;
    brick.sampleBounds(corner, lo, hi);
    // Room for all the brick's samples in both lists (and kEventSlack entries more, for the wide
    // path's whole-vector stores), made once; each part writes at the lists' ends (n, listed)
    // and the lists are cut to them at the end.
    size_t n = s_.samples.size(), listed = 0;
    s_.samples.resize(n + brick.sampleCount + kEventSlack);
    s_.unshadowed.resize(brick.sampleCount + kEventSlack);
    auto takeAll = [&](uint32_t first, uint32_t last) {
        std::iota(s_.unshadowed.begin() + std::ptrdiff_t(listed), s_.unshadowed.begin() + std::ptrdiff_t(listed + (last - first)), first);
        listed += last - first;
        st_.samplesReached += last - first, st_.samplesBoxed += last - first;
    };
    gatherOctants(met, lo, hi, takeAll, n, listed);
    s_.samples.resize(n);
    s_.unshadowed.resize(listed);
}

// gatherBrickSamples' tests of the whole box and of its octants.
template <class TakeAll>
void CylinderTraversal::gatherOctants(const MetBrick& met, const Vec3& lo, const Vec3& hi, TakeAll& takeAll, size_t& n,
                                      size_t& listed) {
    const Brick& brick = tree_.bricks[met.brick];
    const Vec3 corner(met.entry.lo[0], met.entry.lo[1], met.entry.lo[2]);
    if (!brick.divided()) {
        if (boxSurelyUnshadowed(lo, hi)) takeAll(brick.firstSample, brick.firstSample + brick.sampleCount);
        else gatherSampleRange(met.entry, brick.firstSample, brick.firstSample + brick.sampleCount, false, n, listed);
        return;
    }
#if defined(__SSE2__)
    // The eight octants' tests in one step of eight lanes where the CPU has AVX-512, else in two
    // groups of four (octant k: x + 2, y + 2, z + 2 at its bits 0, 1, 2), then each octant read
    // or taken as they say.
    uint32_t may = 0, sure = 0;
    alignas(16) int32_t rect[2][4][4];
#if RS_TRAVERSE_AVX512
    if (sixteen_) boxTests8(corner, lo, hi, may, sure, rect);
    else
#endif
    for (int group = 0; group < 2; ++group) {
        const __m128 offset[3] = {_mm_setr_ps(0.f, 2.f, 0.f, 2.f), _mm_setr_ps(0.f, 0.f, 2.f, 2.f), _mm_set1_ps(2.f * float(group))};
        __m128 partLo[3], partHi[3];
        for (int a = 0; a < 3; ++a) {
            const __m128 octant = _mm_add_ps(_mm_set1_ps(corner[a]), offset[a]);
            partLo[a] = _mm_max_ps(_mm_sub_ps(octant, _mm_set1_ps(kOctantEdge)), _mm_set1_ps(lo[a]));
            partHi[a] = _mm_min_ps(_mm_add_ps(octant, _mm_set1_ps(2.f + kOctantEdge)), _mm_set1_ps(hi[a]));
        }
        uint32_t m, su;
        boxTests4(partLo, partHi, m, su, rect[group]);
        may |= m << (4 * group), sure |= su << (4 * group);
    }
    // Octants read one after another are read as one range, in fewer, fuller groups of lanes:
    // its samples tested one by one unless all its octants are surely reached (a surely reached
    // sample passes the test: the same answers either way). Walked over the bits of the octants
    // to read (holding samples, may be reached): an octant taken whole, or a run from the first
    // octant left up to the next octant with samples that is taken or skipped (octants without
    // samples are passed over). Runs were cut where the test changed, until splitting them cost
    // more than the tests it saved.
    const uint32_t todoAll = may & brick.octantsFilled;
    uint32_t take = 0;
    for (uint32_t bits = todoAll & sure; bits; bits &= bits - 1) {
        const int k = __builtin_ctz(bits), lane = k & 3;
        const int32_t(&r)[4][4] = rect[k >> 2];
        if (rectUnshadowed(r[0][lane], r[1][lane], r[2][lane], r[3][lane])) take |= 1u << k;
    }
    const uint32_t read = todoAll & ~take;
    for (uint32_t todo = todoAll; todo;) {
        const int k = __builtin_ctz(todo);
        if (take >> k & 1u) {
            takeAll(brick.octantBegin(k), brick.octantEnd(k));
            todo &= todo - 1;
            continue;
        }
        const uint32_t stop = brick.octantsFilled & ~read & ~((2u << k) - 1u);
        const int end = stop ? __builtin_ctz(stop) : 8;  // the run is octants [k, end)
        const uint32_t run = read & ((1u << end) - 1u) & ~((1u << k) - 1u);
        gatherSampleRange(met.entry, brick.octantBegin(k), brick.octantEnd(end - 1), (run & ~sure) == 0, n, listed);
        todo &= ~((1u << end) - 1u);
    }
#else
    for (int k = 0; k < 8; ++k) {
        const uint32_t first = brick.octantBegin(k), last = brick.octantEnd(k);
        if (first == last) continue;
        const Vec3 octant = corner + Vec3(float(2 * (k & 1)), float(k & 2), float(k >> 1 & 2));
        const Vec3 partLo = glm::max(lo, octant - kOctantEdge), partHi = glm::min(hi, octant + (2.f + kOctantEdge));
        if (!boxMayBeReached(partLo, partHi)) continue;
        if (boxSurelyUnshadowed(partLo, partHi)) takeAll(first, last);
        else gatherSampleRange(met.entry, first, last, false, n, listed);
    }
#endif
}

// Whether the box [lo, hi] (voxel space) can hold a reached sample: it reaches into the depth
// range (0, L], within h of the axis, in front of the origin's tangent plane. Each test is
// widened by kBoxReachSlack, above the rounding of the per-sample tests, which decide.
bool CylinderTraversal::boxMayBeReached(const Vec3& lo, const Vec3& hi) const {
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) return false;
    const Vec3 c = 0.5f * (lo + hi), half = 0.5f * (hi - lo);
    const Vec3 d = c - o_;
    const float along = glm::dot(d, w_), spread = glm::dot(absW_, half) + kBoxReachSlack;
    if (along + spread <= 0.f || along - spread > L_) return false;
    if (hasNormal_ && glm::dot(d, n_) + glm::dot(absN_, half) + kBoxReachSlack <= 0.f) return false;
    const float reach = radius_ + glm::length(half) + kBoxReachSlack;
    return glm::dot(d, d) - along * along < reach * reach;
}

// Whether every point of the box [lo, hi] (voxel space) is reached — depth in (0, L], within h
// of the axis, in front of the origin's tangent plane — and has a bilinear block no occluder
// can shadow, as reach() and shadowable() decide for a sample. Each bound is narrowed by a
// margin far above the rounding of those per-sample tests (a few ulps of the distances
// involved), so that a sample this lets through is one they let through.
bool CylinderTraversal::boxSurelyUnshadowed(const Vec3& lo, const Vec3& hi) const {
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) return false;
    const Vec3 c = 0.5f * (lo + hi), half = 0.5f * (hi - lo);
    const Vec3 d = c - o_;
    const float halfLength = glm::length(half), size = glm::length(d) + halfLength + 1.f;
    const float slack = kSureSlack + kSureSlackPerSize * size;  // on depths, heights and projections (voxels)
    const float slack2 = kSureSlack2PerSize2 * size * size;    // on squared distances
    const float along = glm::dot(d, w_), spread = glm::dot(absW_, half);
    if (!(along - spread > slack && along + spread <= L_ - slack)) return false;
    if (hasNormal_ && !(glm::dot(d, n_) - glm::dot(absN_, half) > slack)) return false;
    // The distance to the axis line changes by at most the distance moved: no point of the box
    // is farther than the centre's distance + halfLength.
    const float farthest = std::sqrt(std::max(0.f, glm::dot(d, d) - along * along) + slack2) + halfLength + slack;
    if (!(farthest * farthest + slack2 < kernel2_)) return false;
    // The first cells of the box's points' bilinear blocks: a rectangle of the mask.
    const float u = glm::dot(d, aU_), du = glm::dot(absAU_, half) + slack;
    const float v = glm::dot(d, aV_), dv = glm::dot(absAV_, half) + slack;
    const int i0 = floorToInt(u - du - 0.5f) + halfU_, i1 = floorToInt(u + du - 0.5f) + halfU_;
    const int j0 = floorToInt(v - dv - 0.5f) + halfV_, j1 = floorToInt(v + dv - 0.5f) + halfV_;
    return rectUnshadowed(i0, i1, j0, j1);
}

// Whether no cell of the mask rectangle [i0, i1] × [j0, j1] is marked shadowable (false when the
// rectangle leaves the mask).
bool CylinderTraversal::rectUnshadowed(int i0, int i1, int j0, int j1) const {
    if (i0 < 0 || j0 < 0 || i1 >= sizeU_ || j1 >= sizeV_) return false;
    for (int j = j0; j <= j1; ++j) {
        const uint16_t* row = shadow_ + size_t(sizeU_) * size_t(j);
        for (int i = i0; i <= i1; ++i)
            if (row[i] != kNoOccluder) return false;
    }
    return true;
}

#if defined(__SSE2__)
// boxMayBeReached and boxSurelyUnshadowed for four boxes, lane by lane the same operations in
// the same order (so the same answers): bit k of `may` and `sure` for box k, and the mask
// rectangle (i0, i1, j0, j1) that box k's sure test still has to read (rectUnshadowed).
void CylinderTraversal::boxTests4(const __m128 lo[3], const __m128 hi[3], uint32_t& may, uint32_t& sure,
                                  int32_t rect[4][4]) const {
    const __m128 halfOf = _mm_set1_ps(0.5f), zero = _mm_setzero_ps();
    __m128 d[3], half[3], valid = _mm_castsi128_ps(_mm_set1_epi32(-1));
    for (int a = 0; a < 3; ++a) {
        valid = _mm_and_ps(valid, _mm_cmple_ps(lo[a], hi[a]));
        d[a] = _mm_sub_ps(_mm_mul_ps(halfOf, _mm_add_ps(lo[a], hi[a])), four_.o[a]);
        half[a] = _mm_mul_ps(halfOf, _mm_sub_ps(hi[a], lo[a]));
    }
    const __m128 along = dot4(four_.w, d[0], d[1], d[2]), spreadW = dot4(four_.absW, half[0], half[1], half[2]);
    const __m128 spreadN = dot4(four_.absN, half[0], half[1], half[2]), dn = dot4(four_.n, d[0], d[1], d[2]);
    const __m128 halfLength = _mm_sqrt_ps(dot4(half, half[0], half[1], half[2]));
    const __m128 off2 = _mm_sub_ps(dot4(d, d[0], d[1], d[2]), _mm_mul_ps(along, along));
    // boxMayBeReached.
    const __m128 slackM = _mm_set1_ps(kBoxReachSlack), spreadM = _mm_add_ps(spreadW, slackM);
    __m128 m = _mm_and_ps(valid, _mm_and_ps(_mm_cmpnle_ps(_mm_add_ps(along, spreadM), zero),
                                            _mm_cmpngt_ps(_mm_sub_ps(along, spreadM), four_.length)));
    if (hasNormal_) m = _mm_and_ps(m, _mm_cmpnle_ps(_mm_add_ps(_mm_add_ps(dn, spreadN), slackM), zero));
    const __m128 reach = _mm_add_ps(_mm_add_ps(_mm_set1_ps(radius_), halfLength), slackM);
    m = _mm_and_ps(m, _mm_cmplt_ps(off2, _mm_mul_ps(reach, reach)));
    may = uint32_t(_mm_movemask_ps(m));
    // boxSurelyUnshadowed, up to its reading of the map.
    const __m128 size = _mm_add_ps(_mm_add_ps(_mm_sqrt_ps(dot4(d, d[0], d[1], d[2])), halfLength), _mm_set1_ps(1.f));
    const __m128 slack = _mm_add_ps(_mm_set1_ps(kSureSlack), _mm_mul_ps(_mm_set1_ps(kSureSlackPerSize), size));
    const __m128 slack2 = _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(kSureSlack2PerSize2), size), size);
    __m128 s = _mm_and_ps(valid, _mm_and_ps(_mm_cmpgt_ps(_mm_sub_ps(along, spreadW), slack),
                                            _mm_cmple_ps(_mm_add_ps(along, spreadW), _mm_sub_ps(four_.length, slack))));
    if (hasNormal_) s = _mm_and_ps(s, _mm_cmpgt_ps(_mm_sub_ps(dn, spreadN), slack));
    const __m128 farthest = _mm_add_ps(_mm_add_ps(_mm_sqrt_ps(_mm_add_ps(_mm_max_ps(off2, zero), slack2)), halfLength), slack);
    s = _mm_and_ps(s, _mm_cmplt_ps(_mm_add_ps(_mm_mul_ps(farthest, farthest), slack2), four_.kernel2));
    sure = uint32_t(_mm_movemask_ps(s)) & may;
    if (!sure) return;
    const __m128 u = dot4(four_.aU, d[0], d[1], d[2]), du = _mm_add_ps(dot4(four_.absAU, half[0], half[1], half[2]), slack);
    const __m128 v = dot4(four_.aV, d[0], d[1], d[2]), dv = _mm_add_ps(dot4(four_.absAV, half[0], half[1], half[2]), slack);
    _mm_store_si128(reinterpret_cast<__m128i*>(rect[0]), _mm_add_epi32(floorToInt4(_mm_sub_ps(_mm_sub_ps(u, du), halfOf)), four_.halfU));
    _mm_store_si128(reinterpret_cast<__m128i*>(rect[1]), _mm_add_epi32(floorToInt4(_mm_sub_ps(_mm_add_ps(u, du), halfOf)), four_.halfU));
    _mm_store_si128(reinterpret_cast<__m128i*>(rect[2]), _mm_add_epi32(floorToInt4(_mm_sub_ps(_mm_sub_ps(v, dv), halfOf)), four_.halfV));
    _mm_store_si128(reinterpret_cast<__m128i*>(rect[3]), _mm_add_epi32(floorToInt4(_mm_sub_ps(_mm_add_ps(v, dv), halfOf)), four_.halfV));
}
#endif

// Reached samples: inside the cylinder, in front of the origin's tangent plane. Each one's
// projection (u, v) gives its bilinear block; those no occluder can shadow go to the brick's
// unshadowed list, the others become sample events, their voxel (clamped to the brick, where
// the tree put it) giving their slice. Sixteen samples at a time where the CPU has AVX-512,
// else four where SSE is there (the same operations in the same order as the scalar reach(),
// so the same answers).
void CylinderTraversal::gatherSampleRange(const StackEntry& e, uint32_t first, uint32_t last, bool surelyReached,
                                          size_t& events, size_t& listed) {
#if RS_TRAVERSE_AVX512
    if (sixteen_) return gatherSampleRange16(e, first, last, surelyReached, events, listed);
#endif
    // The events are written field by field into the room made by the caller: a pushed
    // temporary would be built on the stack and reloaded whole, a store-forwarding stall per
    // sample.
    size_t n = events, free = listed;
    const int layerLo = e.lo[N_], layerHi = int(e.hi[N_]) - 1;
    int sliceMin = sliceMin_, sliceMax = sliceMax_;  // kept in registers, not written through `this`
    uint32_t i = first;
#if defined(__SSE2__)
    auto fours = [&](auto test) {
        for (; i + 4 <= last; i += 4) {
            Reach4 r;
            for (uint32_t bits = reach4<decltype(test)::value>(&eye_.position[i], r); bits; bits &= bits - 1) {
                const int k = __builtin_ctz(bits);
                addReached(i + uint32_t(k), Reach{r.u[k], r.v[k], r.i0[k], r.j0[k], r.voxelN[k]}, layerLo, layerHi, n, free,
                           sliceMin, sliceMax);
            }
        }
    };
    if (surelyReached) fours(std::false_type{});
    else fours(std::true_type{});
#endif
    gatherSampleScalar(e, i, last, n, free, sliceMin, sliceMax);
    sliceMin_ = sliceMin, sliceMax_ = sliceMax;
    st_.samplesReached += n + free - events - listed;
    st_.samplesTested += last - first;
    events = n, listed = free;
}

// The samples [first, last) one by one (reach(), then addReached).
void CylinderTraversal::gatherSampleScalar(const StackEntry& e, uint32_t first, uint32_t last, size_t& events,
                                           size_t& listed, int& sliceMin, int& sliceMax) {
    const int layerLo = e.lo[N_], layerHi = int(e.hi[N_]) - 1;
    for (uint32_t i = first; i < last; ++i) {
        Reach r;
        if (reach(eye_.position[i], r)) addReached(i, r, layerLo, layerHi, events, listed, sliceMin, sliceMax);
    }
}

// A reached sample's slice is its voxel layer's (clamped to the brick's, where the tree put
// it). One that no occluder of an earlier slice can shadow goes to the unshadowed list, another
// becomes an event in its slice.
inline void CylinderTraversal::addReached(uint32_t i, const Reach& r, int layerLo, int layerHi, size_t& events,
                                          size_t& listed, int& sliceMin, int& sliceMax) {
    const int slice = sliceOf(std::clamp(r.voxelN, layerLo, layerHi));
    if (slice <= firstShadowingSlice(r.i0, r.j0)) {
        s_.unshadowed[listed++] = i;
        return;
    }
    SampleEvent& ev = s_.samples[events++];
    ev.index = i;
    ev.slice = slice;
    ++s_.sampleSlices[size_t(slice)];
    sliceMin = std::min(sliceMin, slice), sliceMax = std::max(sliceMax, slice);
    ev.u = r.u;
    ev.v = r.v;
}

// A sample at world position y is reached: at p = its voxel-space position, depth in (0, L],
// within h of the axis line, in front of the origin's tangent plane. Then its projection:
// u = (p − o)·aU, v = (p − o)·aV (aU = e_U − k_U e_N: the same value as (p_U − o_U) −
// k_U (p_N − o_N)), the bilinear block's first cell (i0, j0) and the voxel layer along N.
inline bool CylinderTraversal::reach(const Vec3& y, Reach& r) const {
    const Vec3 p = (y - g_.origin) * invVoxel_;
    const Vec3 d = p - o_;
    const float along = glm::dot(d, w_);
    if (!(along > 0.f && along <= L_) || glm::dot(d, d) - along * along >= kernel2_) return false;
    if (hasNormal_ && glm::dot(d, n_) <= 0.f) return false;
    r.u = glm::dot(d, aU_), r.v = glm::dot(d, aV_);
    r.i0 = floorToInt(r.u - 0.5f) + halfU_, r.j0 = floorToInt(r.v - 0.5f) + halfV_;
    r.voxelN = floorToInt(p[N_]);
    return true;
}

#if defined(__SSE2__)
// reach() for the four samples at `world` (consecutive), bit k for sample k. Each comparison is
// the negation reach() rejects by, so a NaN goes the same way. Without kTest (samples of a box
// whose every point boxTests4 found reached) only the projection is made, every lane reached.
template <bool kTest>
uint32_t CylinderTraversal::reach4(const Vec3* world, Reach4& r) const {
    // Four packed xyz triples to x, y, z lanes.
    const float* f = &world[0].x;
    const __m128 a = _mm_loadu_ps(f), b = _mm_loadu_ps(f + 4), c = _mm_loadu_ps(f + 8);
    const __m128 wx = _mm_shuffle_ps(a, _mm_shuffle_ps(b, c, _MM_SHUFFLE(1, 1, 2, 2)), _MM_SHUFFLE(2, 0, 3, 0));
    const __m128 wy = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(0, 0, 1, 1)), _mm_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 3)),
                                     _MM_SHUFFLE(2, 0, 2, 0));
    const __m128 wz = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 1, 2, 2)), _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 0, 0)),
                                     _MM_SHUFFLE(2, 0, 2, 0));
    const __m128 p[3] = {_mm_mul_ps(_mm_sub_ps(wx, four_.gridOrigin[0]), four_.invVoxel),
                         _mm_mul_ps(_mm_sub_ps(wy, four_.gridOrigin[1]), four_.invVoxel),
                         _mm_mul_ps(_mm_sub_ps(wz, four_.gridOrigin[2]), four_.invVoxel)};
    const __m128 dx = _mm_sub_ps(p[0], four_.o[0]), dy = _mm_sub_ps(p[1], four_.o[1]), dz = _mm_sub_ps(p[2], four_.o[2]);
    uint32_t bits = 15u;
    if constexpr (kTest) {
        const __m128 along = dot4(four_.w, dx, dy, dz);
        const __m128 dd = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
        __m128 ok = _mm_and_ps(_mm_cmpgt_ps(along, _mm_setzero_ps()), _mm_cmple_ps(along, four_.length));
        ok = _mm_and_ps(ok, _mm_cmpnge_ps(_mm_sub_ps(dd, _mm_mul_ps(along, along)), four_.kernel2));
        if (hasNormal_) ok = _mm_and_ps(ok, _mm_cmpnle_ps(dot4(four_.n, dx, dy, dz), _mm_setzero_ps()));
        bits = uint32_t(_mm_movemask_ps(ok));
        if (!bits) return 0;
    }
    const __m128 u = dot4(four_.aU, dx, dy, dz), v = dot4(four_.aV, dx, dy, dz), half = _mm_set1_ps(0.5f);
    _mm_store_ps(r.u, u), _mm_store_ps(r.v, v);
    _mm_store_si128(reinterpret_cast<__m128i*>(r.i0), _mm_add_epi32(floorToInt4(_mm_sub_ps(u, half)), four_.halfU));
    _mm_store_si128(reinterpret_cast<__m128i*>(r.j0), _mm_add_epi32(floorToInt4(_mm_sub_ps(v, half)), four_.halfV));
    _mm_store_si128(reinterpret_cast<__m128i*>(r.voxelN), floorToInt4(p[N_]));
    return bits;
}
#endif
// -- The slice sweep (§5.1) -------------------------------------------------------------------

#if defined(__SSE2__)
// read() for four sample events, lane by lane the same operations in the same order (so the
// same values): the four events' cells and rows' valid ranges loaded per lane, then turned so
// that each vector holds one corner of the four blocks.
void CylinderTraversal::read4(const SampleEvent* ev, float vis[4]) const {
    static_assert(sizeof(SampleEvent) == 16, "an event is one vector: index, slice, u, v");
    __m128 r[4];
    for (int k = 0; k < 4; ++k) r[k] = _mm_loadu_ps(reinterpret_cast<const float*>(ev + k));
    _MM_TRANSPOSE4_PS(r[0], r[1], r[2], r[3]);  // the indices, slices, u's and v's
    const __m128 half = _mm_set1_ps(0.5f), x = _mm_sub_ps(r[2], half), y = _mm_sub_ps(r[3], half);
    const __m128i ix = floorToInt4(x), iy = floorToInt4(y);
    const __m128 fx = _mm_sub_ps(x, _mm_cvtepi32_ps(ix)), fy = _mm_sub_ps(y, _mm_cvtepi32_ps(iy));
    const __m128i i0 = _mm_add_epi32(ix, _mm_set1_epi32(halfU_)), j0 = _mm_add_epi32(iy, _mm_set1_epi32(halfV_));
    alignas(16) int32_t is[4], js[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(is), i0);
    _mm_store_si128(reinterpret_cast<__m128i*>(js), j0);
    __m128 cell[4], range[4];
    for (int k = 0; k < 4; ++k) {
        if (!(unsigned(is[k]) < unsigned(sizeU_ - 1) && unsigned(js[k]) < unsigned(sizeV_ - 1))) {
            for (int m = 0; m < 4; ++m) vis[m] = read(ev[m]);  // a block at the mask's edge (none, by its size)
            return;
        }
        const float* row0 = &s_.sweep[size_t(is[k]) + size_t(sizeU_) * size_t(js[k])];
        cell[k] = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(row0)),
                               reinterpret_cast<const __m64*>(row0 + sizeU_));
        range[k] = _mm_loadu_ps(reinterpret_cast<const float*>(&s_.rows[size_t(js[k])]));  // lo0 hi0 lo1 hi1
    }
    _MM_TRANSPOSE4_PS(cell[0], cell[1], cell[2], cell[3]);     // corners (0,0) (1,0) (0,1) (1,1)
    _MM_TRANSPOSE4_PS(range[0], range[1], range[2], range[3]);  // lo0 hi0 lo1 hi1
    const __m128i i1 = _mm_add_epi32(i0, _mm_set1_epi32(1));
    auto outside = [](__m128i i, __m128 lo, __m128 hi) {
        return _mm_castsi128_ps(_mm_or_si128(_mm_cmplt_epi32(i, _mm_castps_si128(lo)), _mm_cmpgt_epi32(i, _mm_castps_si128(hi))));
    };
    const __m128 one = _mm_set1_ps(1.f), gx = _mm_sub_ps(one, fx), gy = _mm_sub_ps(one, fy);
    const __m128 w[4] = {_mm_andnot_ps(outside(i0, range[0], range[1]), _mm_mul_ps(gx, gy)),
                         _mm_andnot_ps(outside(i1, range[0], range[1]), _mm_mul_ps(fx, gy)),
                         _mm_andnot_ps(outside(i0, range[2], range[3]), _mm_mul_ps(gx, fy)),
                         _mm_andnot_ps(outside(i1, range[2], range[3]), _mm_mul_ps(fx, fy))};
    __m128 t[4];
    for (int k = 0; k < 4; ++k) t[k] = _mm_mul_ps(w[k], _mm_min_ps(one, cell[k]));
    // (t0 + t2) + (t1 + t3), as read() adds its lanes.
    const __m128 num = _mm_add_ps(_mm_add_ps(t[0], t[2]), _mm_add_ps(t[1], t[3]));
    const __m128 den = _mm_add_ps(_mm_add_ps(w[0], w[2]), _mm_add_ps(w[1], w[3]));
    const __m128 lit = _mm_cmpgt_ps(num, _mm_setzero_ps());
    const __m128 shadowed = _mm_sub_ps(one, _mm_div_ps(num, _mm_or_ps(den, _mm_andnot_ps(lit, one))));
    _mm_store_ps(vis, _mm_or_ps(_mm_and_ps(lit, shadowed), _mm_andnot_ps(lit, one)));
}
#endif

// Sorts the sample events by slice, and the occluder events of their slices (counting sorts,
// stable, over the per-slice counts made with the events). Occluders before the first sample's
// slice are read by every sample: added at once; those after the last one's, by none.
void CylinderTraversal::prepareSweep() {
    s_.samplesSorted.clear();
    s_.occludersSorted.clear();
    st_.samplesSwept += s_.samples.size();
    if (s_.samples.empty()) return;
    // Counts to first positions, in place.
    auto offsets = [](uint32_t* count, int lo, int hi) {
        uint32_t at = 0;
        for (int i = lo; i <= hi; ++i) {
            const uint32_t c = count[i];
            count[i] = at, at += c;
        }
        return at;
    };
    s_.samplesSorted.resize(offsets(s_.sampleSlices.data(), sliceMin_, sliceMax_));
    for (const SampleEvent& ev : s_.samples) s_.samplesSorted[s_.sampleSlices[size_t(ev.slice)]++] = ev;
    const int lo = std::max(sliceMin_, occluderMin_), hi = std::min(sliceMax_, occluderMax_);
    s_.occludersSorted.resize(lo <= hi ? offsets(s_.occluderSlices.data(), lo, hi) : 0);
    for (const OccluderEvent& ev : s_.occluders) {
        if (ev.slice < sliceMin_) s_.sweep[size_t(ev.cell)] += ev.occ;
        else if (ev.slice <= sliceMax_) s_.occludersSorted[s_.occluderSlices[size_t(ev.slice)]++] = ev;
    }
}

}  // namespace rs
