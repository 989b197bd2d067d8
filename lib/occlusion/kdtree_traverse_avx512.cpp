// The traversal's sixteen-lane steps, on CPUs with AVX-512 (chosen at run time: the build
// assumes only x86-64's SSE2): the reach test, a brick's candidate occluders and the sweep's
// reads, and a brick's eight octant box tests in one step of eight lanes. Each lane makes the
// same operations in the same order as the four-lane step (the build does not contract a
// product and a sum into one rounding), so the lists, events and values are the same, in the
// same order, as the four-lane path makes them.
#include "occlusion/kdtree_traverse.h"

#include <cstring>

#if defined(__GNUC__) && !defined(__clang__)
// GCC 12 warns of the unset vector its own AVX-512 intrinsics start from (_mm512_undefined_*).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
#endif

namespace rs {

using namespace kd_detail;

#if RS_TRAVERSE_AVX512

struct CylinderTraversal::Occluders16 {
    __mmask16 met;   // the lanes that are met voxels
    __m512i voxel;   // their occlusion counts
    __m512i layer;   // their layer along N
    __m512i cu, cv;  // their centres' mask cell
    __mmask16 inMask;
};

namespace {

// Lane l of a deinterleave of 48 packed floats (16 xyz triples in three vectors a, b, c):
// component `comp` of triple l is float 3l + comp. First a two-source permute of a and b
// (lanes whose float lies in c get anything), then one of that and c.
struct Deinterleave {
    alignas(64) int32_t ab[3][16], c[3][16];
    Deinterleave() {
        for (int comp = 0; comp < 3; ++comp)
            for (int l = 0; l < 16; ++l) {
                const int f = 3 * l + comp, source = f / 16, within = f % 16;
                ab[comp][l] = source < 2 ? (source << 4 | within) : 0;
                c[comp][l] = source == 2 ? (16 | within) : l;
            }
    }
};
const Deinterleave kDeinterleave;

// dot4 in sixteen lanes: (x·v₀ + y·v₁) + z·v₂, glm::dot's order.
__attribute__((target("avx512f"))) inline __m512 dot16(const __m512 v[3], __m512 x, __m512 y, __m512 z) {
    return _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(x, v[0]), _mm512_mul_ps(y, v[1])), _mm512_mul_ps(z, v[2]));
}

// floorToInt lane by lane: truncate, then step down where that went up.
__attribute__((target("avx512f"))) inline __m512i floor16(__m512 x) {
    const __m512i t = _mm512_cvttps_epi32(x);
    const __mmask16 up = _mm512_cmp_ps_mask(x, _mm512_cvtepi32_ps(t), _CMP_LT_OS);
    return _mm512_mask_sub_epi32(t, up, t, _mm512_set1_epi32(1));
}

// A mask of the first `count` lanes (none when count ≤ 0).
__attribute__((target("avx512f"))) inline __mmask16 firstLanes(int count) {
    return count >= 16 ? __mmask16(0xffff) : __mmask16((1u << unsigned(std::max(count, 0))) - 1u);
}

// The 64-bit words at base + 4·index for the `active` lanes, eight lanes at a time, split into
// their low (even) and high (odd) 32-bit halves.
__attribute__((target("avx512f"))) inline void gatherPairs(__mmask16 active, __m512i index, const void* base, __m512i& even,
                                                           __m512i& odd) {
    const __m512i a = _mm512_mask_i32gather_epi64(_mm512_setzero_si512(), __mmask8(active), _mm512_castsi512_si256(index), base, 4);
    const __m512i b =
        _mm512_mask_i32gather_epi64(_mm512_setzero_si512(), __mmask8(active >> 8), _mm512_extracti64x4_epi64(index, 1), base, 4);
    even = _mm512_permutex2var_epi32(a, _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30), b);
    odd = _mm512_permutex2var_epi32(a, _mm512_setr_epi32(1, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31), b);
}

// A bilinear weight, made 0 where the cell is not valid (its value, as an integer, negative:
// kInvalidCell; a valid cell's sum is +0 or more).
__attribute__((target("avx512f"))) inline __m512 validWeight(__m512i cell, __m512 w) {
    return _mm512_maskz_mov_ps(_mm512_cmp_epi32_mask(cell, _mm512_setzero_si512(), _MM_CMPINT_NLT), w);
}

// weight × min(1, cell value).
__attribute__((target("avx512f"))) inline __m512 cellTerm(__m512 w, __m512i c) {
    return _mm512_mul_ps(w, _mm512_min_ps(_mm512_set1_ps(1.f), _mm512_castsi512_ps(c)));
}

// The positions of `count` (1…16) consecutive samples in lanes, in voxel space (p) and from
// the cylinder's origin (d = p − o), as reach() makes them: three masked loads (the floats past
// the last sample not read; a masked load does not fault) deinterleaved by two permutes each.
struct SampleLanes {
    __m512 p[3], d[3];
};
__attribute__((target("avx512f"), always_inline)) inline SampleLanes loadSamples16(const float* f, int count,
                                                                                   const __m512 origin[3], __m512 invVoxel,
                                                                                   const __m512 o[3], const __m512i ab[3],
                                                                                   const __m512i c[3]) {
    const __m512 va = _mm512_maskz_loadu_ps(firstLanes(3 * count), f);
    const __m512 vb = _mm512_maskz_loadu_ps(firstLanes(3 * count - 16), f + 16);
    const __m512 vc = _mm512_maskz_loadu_ps(firstLanes(3 * count - 32), f + 32);
    SampleLanes s;
    for (int a = 0; a < 3; ++a) {
        const __m512 world = _mm512_permutex2var_ps(_mm512_permutex2var_ps(va, ab[a], vb), c[a], vc);
        s.p[a] = _mm512_mul_ps(_mm512_sub_ps(world, origin[a]), invVoxel);
        s.d[a] = _mm512_sub_ps(s.p[a], o[a]);
    }
    return s;
}

// reach()'s tests for the `lanes` given: depth in (0, L], distance to the axis line < h, and,
// where the origin has a normal n (else null), in front of its tangent plane.
__attribute__((target("avx512f"), always_inline)) inline __mmask16 reachLanes16(__mmask16 lanes, const __m512 d[3],
                                                                                const __m512 w[3], __m512 length,
                                                                                __m512 kernel2, const __m512* n) {
    const __m512 zero = _mm512_setzero_ps(), along = dot16(w, d[0], d[1], d[2]);
    const __m512 dd = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(d[0], d[0]), _mm512_mul_ps(d[1], d[1])), _mm512_mul_ps(d[2], d[2]));
    lanes = _mm512_mask_cmp_ps_mask(lanes, along, zero, _CMP_GT_OQ);
    lanes = _mm512_mask_cmp_ps_mask(lanes, along, length, _CMP_LE_OQ);
    lanes = _mm512_mask_cmp_ps_mask(lanes, _mm512_sub_ps(dd, _mm512_mul_ps(along, along)), kernel2, _CMP_NGE_UQ);
    if (n) lanes = _mm512_mask_cmp_ps_mask(lanes, dot16(n, d[0], d[1], d[2]), zero, _CMP_NLE_UQ);
    return lanes;
}

// Sample events {index, slice, u, v} of the `shadowed` lanes, compressed and turned into
// records, sixteen stored whole at `out` (the lists have room to spare past their ends).
__attribute__((target("avx512f"), always_inline)) inline void writeEvents16(__mmask16 shadowed, __m512i index, __m512i slice,
                                                                            __m512 u, __m512 v, SampleEvent* out) {
    const __m512i ci = _mm512_maskz_compress_epi32(shadowed, index), cs = _mm512_maskz_compress_epi32(shadowed, slice);
    const __m512i cu = _mm512_castps_si512(_mm512_maskz_compress_ps(shadowed, u));
    const __m512i cv = _mm512_castps_si512(_mm512_maskz_compress_ps(shadowed, v));
    const __m512i t0 = _mm512_unpacklo_epi32(ci, cs), t1 = _mm512_unpackhi_epi32(ci, cs);
    const __m512i t2 = _mm512_unpacklo_epi32(cu, cv), t3 = _mm512_unpackhi_epi32(cu, cv);
    const __m512i r0 = _mm512_unpacklo_epi64(t0, t2), r1 = _mm512_unpackhi_epi64(t0, t2);  // events 4k, 4k + 1
    const __m512i r2 = _mm512_unpacklo_epi64(t1, t3), r3 = _mm512_unpackhi_epi64(t1, t3);  // 4k + 2, 4k + 3
    const __m512i q0 = _mm512_shuffle_i32x4(r0, r1, _MM_SHUFFLE(1, 0, 1, 0)), q1 = _mm512_shuffle_i32x4(r2, r3, _MM_SHUFFLE(1, 0, 1, 0));
    const __m512i q2 = _mm512_shuffle_i32x4(r0, r1, _MM_SHUFFLE(3, 2, 3, 2)), q3 = _mm512_shuffle_i32x4(r2, r3, _MM_SHUFFLE(3, 2, 3, 2));
    _mm512_storeu_si512(out, _mm512_shuffle_i32x4(q0, q1, _MM_SHUFFLE(2, 0, 2, 0)));
    _mm512_storeu_si512(out + 4, _mm512_shuffle_i32x4(q0, q1, _MM_SHUFFLE(3, 1, 3, 1)));
    _mm512_storeu_si512(out + 8, _mm512_shuffle_i32x4(q2, q3, _MM_SHUFFLE(2, 0, 2, 0)));
    _mm512_storeu_si512(out + 12, _mm512_shuffle_i32x4(q2, q3, _MM_SHUFFLE(3, 1, 3, 1)));
}

// Occluder events {cell, slice, occ} (twelve bytes) of the `keep` lanes, compressed and
// interleaved, sixteen stored whole at `out` (the list has room to spare past its end).
__attribute__((target("avx512f"), always_inline)) inline void writeOccluders16(__mmask16 keep, __m512i cell, __m512i slice,
                                                                               __m512 occ, OccluderEvent* out) {
    static_assert(sizeof(OccluderEvent) == 12, "an occluder event is three 32-bit words: cell, slice, occ");
    const __m512i c = _mm512_maskz_compress_epi32(keep, cell), s = _mm512_maskz_compress_epi32(keep, slice);
    const __m512i o = _mm512_castps_si512(_mm512_maskz_compress_ps(keep, occ));
    // Word d of the three vectors is field d mod 3 of event d / 3: the cells and slices by one
    // two-source permute, the occlusions put in by a masked one.
    static const int32_t cellSlice[3][16] = {{0, 16, 0, 1, 17, 0, 2, 18, 0, 3, 19, 0, 4, 20, 0, 5},
                                             {21, 0, 6, 22, 0, 7, 23, 0, 8, 24, 0, 9, 25, 0, 10, 26},
                                             {0, 11, 27, 0, 12, 28, 0, 13, 29, 0, 14, 30, 0, 15, 31, 0}};
    static const int32_t event[3][16] = {{0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3, 4, 4, 4, 5},
                                         {5, 5, 6, 6, 6, 7, 7, 7, 8, 8, 8, 9, 9, 9, 10, 10},
                                         {10, 11, 11, 11, 12, 12, 12, 13, 13, 13, 14, 14, 14, 15, 15, 15}};
    constexpr __mmask16 occWord[3] = {0x4924, 0x2492, 0x9249};
    int32_t* words = reinterpret_cast<int32_t*>(out);
    for (int j = 0; j < 3; ++j) {
        const __m512i cs = _mm512_permutex2var_epi32(c, _mm512_loadu_si512(cellSlice[j]), s);
        _mm512_storeu_si512(words + 16 * j, _mm512_mask_permutexvar_epi32(cs, occWord[j], _mm512_loadu_si512(event[j]), o));
    }
}

}  // namespace

// findValidRows with every cell of the mask tested, sixteen at a time, by validCell's operations
// (with q_N = 0 its dot products are q_U ω_U + q_V ω_V and q_U² + q_V², to the bit): a row whose
// valid cells are one run inside the mask, not touching its sides, is that run; another (empty in
// the mask, or one that may go on past it) is left to findValidRow, so that the rows are the same.
__attribute__((target("avx512f"))) void CylinderTraversal::findValidRows16() {
    const __m512 wU = _mm512_set1_ps(w_[U_]), wV = _mm512_set1_ps(w_[V_]), valid2 = _mm512_set1_ps(valid2_);
    const __m512 half = _mm512_set1_ps(0.5f);
    const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    const int chunks = (sizeU_ + 15) / 16;
    for (int j = 0; j < sizeV_; ++j) {
        const __m512 qV = _mm512_add_ps(_mm512_set1_ps(float(j - halfV_)), half);
        const __m512 b = _mm512_mul_ps(qV, wV), qV2 = _mm512_mul_ps(qV, qV);
        int lo = -1, hi = -1;
        bool run = true;  // the valid cells so far are one run
        for (int c = 0; c < chunks && run; ++c) {
            const __m512 qU = _mm512_add_ps(_mm512_cvtepi32_ps(_mm512_add_epi32(lane, _mm512_set1_epi32(16 * c - halfU_))), half);
            const __m512 along = _mm512_add_ps(_mm512_mul_ps(qU, wU), b);
            const __m512 dd = _mm512_add_ps(_mm512_mul_ps(qU, qU), qV2);
            const unsigned valid = unsigned(_mm512_mask_cmp_ps_mask(firstLanes(sizeU_ - 16 * c), _mm512_sub_ps(dd, _mm512_mul_ps(along, along)),
                                                                    valid2, _CMP_LE_OQ));
            if (!valid) continue;
            const int first = 16 * c + __builtin_ctz(valid), last = 16 * c + 31 - __builtin_clz(valid);
            if (hi >= 0 && first != hi + 1) run = false;  // a gap, or a run that does not go on
            if (valid != ((2u << (last - 16 * c)) - (1u << (first - 16 * c)))) run = false;
            if (lo < 0) lo = first;
            hi = last;
        }
        if (lo < 0) {
            // No valid cell in the mask: findValidRow finds none either when the three cells it
            // tries first, around the minimum of the row's distances, lie in the mask.
            const int ic = int(std::floor(rowMinimum(j))) + halfU_;
            s_.rows[size_t(j)] = ic >= 1 && ic < sizeU_ - 1 ? RowRange{INT_MAX / 2, INT_MIN / 2} : findValidRow(j);
            continue;
        }
        s_.rows[size_t(j)] = run && lo > 0 && hi < sizeU_ - 1 ? RowRange{lo, hi} : findValidRow(j);
    }
}

// gatherBrick's candidates sixteen at a time, in bit order: their bit numbers compressed out of
// the brick's four layers (a wall across x or y has four candidates a layer: one group for the
// brick where there were four), then the tangent test, the sure met test and the centres' cells
// in lanes, the same operations in the same order as the four-lane step; the valid-cell test by
// a gather of the cells' values (markInvalidCells); the exact met test for the lanes the sure
// one left, lane by lane; then the met voxels' occluders in lanes (addOccluders16), in bit order.
__attribute__((target("avx512f"))) void CylinderTraversal::gatherBrickOccluders16(const StackEntry& e, const Brick& brick,
                                                                                   uint64_t candidates) {
    const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15), three = _mm512_set1_epi32(3);
    // The candidates' bit numbers in order (compressed in registers, stored whole: the list has
    // room for sixteen past its end).
    alignas(64) int32_t bitOf[64 + 16];
    int count = 0;
    for (int layer = 0; layer < kBrickSize; ++layer) {
        const __mmask16 bits = __mmask16(candidates >> (16 * layer));
        if (!bits) continue;
        _mm512_storeu_si512(bitOf + count, _mm512_maskz_compress_epi32(bits, _mm512_add_epi32(lane, _mm512_set1_epi32(16 * layer))));
        count += __builtin_popcount(bits);
    }
    const __m512i corner[3] = {_mm512_set1_epi32(e.lo[0]), _mm512_set1_epi32(e.lo[1]), _mm512_set1_epi32(e.lo[2])};
    __m512 o[3], w[3], nrm[3], aU[3], aV[3];
    for (int a = 0; a < 3; ++a) {
        o[a] = _mm512_set1_ps(o_[a]), w[a] = _mm512_set1_ps(w_[a]), nrm[a] = _mm512_set1_ps(n_[a]);
        aU[a] = _mm512_set1_ps(aU_[a]), aV[a] = _mm512_set1_ps(aV_[a]);
    }
    const __m512 half = _mm512_set1_ps(0.5f), zero = _mm512_setzero_ps();
    const __m512i sizeU = _mm512_set1_epi32(sizeU_), sizeV = _mm512_set1_epi32(sizeV_);
    const float* sweep = s_.sweep.data();
    const VoxelOcclusion* voxels = tree_.voxels.data();
    // Room for every candidate's event and a whole vector's more.
    size_t n = s_.occluders.size();
    s_.occluders.resize(n + size_t(count) + kEventSlack);
    for (int group = 0; group < count; group += 16) {
        const __mmask16 bits = firstLanes(count - group);
        const __m512i b = _mm512_loadu_si512(bitOf + group);
        const __m512i vi[3] = {_mm512_add_epi32(corner[0], _mm512_and_si512(b, three)),
                               _mm512_add_epi32(corner[1], _mm512_and_si512(_mm512_srli_epi32(b, 2), three)),
                               _mm512_add_epi32(corner[2], _mm512_srli_epi32(b, 4))};
        __m512 d[3];
        for (int a = 0; a < 3; ++a) d[a] = _mm512_sub_ps(_mm512_add_ps(_mm512_cvtepi32_ps(vi[a]), half), o[a]);
        const __mmask16 front =
            hasNormal_ ? _mm512_mask_cmp_ps_mask(bits, dot16(nrm, d[0], d[1], d[2]), _mm512_set1_ps(tangentOffset_), _CMP_GT_OS) : bits;
        if (!front) continue;
        const __m512 along = dot16(w, d[0], d[1], d[2]), dd = dot16(d, d[0], d[1], d[2]);
        __mmask16 sure = _mm512_cmp_ps_mask(along, zero, _CMP_GE_OS);
        sure = _mm512_mask_cmp_ps_mask(sure, along, _mm512_set1_ps(L_), _CMP_LE_OS);
        sure = _mm512_mask_cmp_ps_mask(sure, _mm512_sub_ps(dd, _mm512_mul_ps(along, along)), _mm512_set1_ps(hOcc_ * hOcc_),
                                       _CMP_LT_OS);
        const __m512i cu = _mm512_add_epi32(floor16(dot16(aU, d[0], d[1], d[2])), _mm512_set1_epi32(halfU_));
        const __m512i cv = _mm512_add_epi32(floor16(dot16(aV, d[0], d[1], d[2])), _mm512_set1_epi32(halfV_));
        // invalidCell: inside the mask and holding kInvalidCell (no occluder is in the mask yet,
        // so a valid cell holds +0).
        const __mmask16 inMask =
            _mm512_mask_cmp_epu32_mask(_mm512_mask_cmp_epu32_mask(front, cu, sizeU, _MM_CMPINT_LT), cv, sizeV, _MM_CMPINT_LT);
        const __m512i value = _mm512_mask_i32gather_epi32(_mm512_setzero_si512(), inMask, _mm512_add_epi32(cu, _mm512_mullo_epi32(cv, sizeU)),
                                                          sweep, 4);
        const __mmask16 invalid = _mm512_mask_cmp_epi32_mask(inMask, value, _mm512_setzero_si512(), _MM_CMPINT_LT);
        const __mmask16 keep = front & ~invalid;
        if (!keep) continue;
        // The exact met test for the lanes the sure one left, lane by lane (few are).
        __mmask16 met = keep & sure;
        for (unsigned k = keep & ~sure; k; k &= k - 1) {
            const int l = __builtin_ctz(k), bit = bitOf[group + l];
            if (voxelMet(e.lo[0] + (bit & 3), e.lo[1] + (bit >> 2 & 3), e.lo[2] + (bit >> 4))) met |= __mmask16(1u << l);
        }
        if (!met) continue;
        // Where the met voxels' counts are: the rank of a bit among the occupied ones.
        alignas(64) int32_t at[16];
        for (unsigned k = met; k; k &= k - 1) {
            const int l = __builtin_ctz(k);
            at[l] = int32_t(brick.firstVoxel) + __builtin_popcountll(brick.occupied & ((uint64_t(1) << bitOf[group + l]) - 1));
        }
        const __m512i voxel = _mm512_mask_i32gather_epi32(_mm512_setzero_si512(), met, _mm512_maskz_loadu_epi32(met, at),
                                                          voxels, 4);
        n = addOccluders16(Occluders16{met, voxel, vi[N_], cu, cv, inMask}, n);
    }
    s_.occluders.resize(n);
}

// addOccluderAt for the `met` lanes (voxel counts, layer along N, cell), the same operations in
// the same order, so the same events in the same (bit) order, written at s_.occluders[n]; returns
// the list's new end.
__attribute__((target("avx512f"))) size_t CylinderTraversal::addOccluders16(const Occluders16& c, size_t n) {
    const __mmask16 met = c.met, inMask = c.inMask;
    const __m512i voxel = c.voxel, layer = c.layer, cu = c.cu, cv = c.cv;
    // occ = min(1, Σ_a occWeight_a · count(side_a)), summed from a = 0 as addOccluderAt does.
    __m512 occ = _mm512_setzero_ps();
    for (int a = 0; a < 3; ++a) {
        const __m512i count = _mm512_and_si512(_mm512_srlv_epi32(voxel, _mm512_set1_epi32(5 * side_[a])), _mm512_set1_epi32(31));
        occ = _mm512_add_ps(occ, _mm512_mul_ps(_mm512_set1_ps(occWeight_[a]), _mm512_cvtepi32_ps(count)));
    }
    occ = _mm512_min_ps(occ, _mm512_set1_ps(1.f));
    const __mmask16 occludes = _mm512_mask_cmp_ps_mask(met, occ, _mm512_setzero_ps(), _CMP_GT_OQ);
    // The slice: the layer's, pushed by ambOffset_ of the dominant axis where ambiguous (both
    // counts of an axis non-zero).
    const __m512i field = _mm512_set1_epi32(31);
    __mmask16 ambiguous = 0;
    for (int a = 0; a < 3; ++a)
        ambiguous |= _mm512_test_epi32_mask(voxel, _mm512_slli_epi32(field, 10 * a)) &
                     _mm512_test_epi32_mask(voxel, _mm512_slli_epi32(field, 10 * a + 5));
    const __m512i offset = _mm512_permutexvar_epi32(_mm512_srli_epi32(voxel, 30), _mm512_setr_epi32(ambOffset_[0], ambOffset_[1],
                                                                                                      ambOffset_[2], 0, 0, 0, 0, 0, 0,
                                                                                                      0, 0, 0, 0, 0, 0, 0));
    __m512i slice = forward_ ? layer : _mm512_sub_epi32(_mm512_set1_epi32(dimN_ - 1), layer);
    slice = _mm512_mask_add_epi32(slice, ambiguous, slice, offset);
    RS_DCHECK((occludes & ~inMask) == 0);  // inside the mask by construction, as in addOccluderAt
    const __mmask16 keep = occludes & inMask;
    if (!keep) return n;
    writeOccluders16(keep, _mm512_add_epi32(cu, _mm512_mullo_epi32(cv, _mm512_set1_epi32(sizeU_))), slice, occ, &s_.occluders[n]);
    alignas(64) int32_t slices[16];
    _mm512_store_si512(slices, _mm512_maskz_compress_epi32(keep, slice));
    const int kept = __builtin_popcount(keep);
    for (int k = 0; k < kept; ++k) ++s_.occluderSlices[size_t(slices[k])];
    occluderMin_ = std::min(occluderMin_, _mm512_mask_reduce_min_epi32(keep, slice));
    occluderMax_ = std::max(occluderMax_, _mm512_mask_reduce_max_epi32(keep, slice));
    st_.occluders += uint64_t(kept);
    return n + size_t(kept);
}

// boxTests4 for a divided brick's eight octants at once (octant k: x + 2, y + 2, z + 2 at its
// bits 0, 1, 2), each clipped to the box [lo, hi] its samples lie in, eight lanes wide: lane by
// lane the same operations in the same order, so the same answers. rect[k >> 2][row][k & 3] is
// octant k's rectangle, as boxTests4 leaves it for its group of four.
namespace {
__attribute__((target("avx512f"), always_inline)) inline __m256 dot8(const __m256 v[3], __m256 x, __m256 y, __m256 z) {
    return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, v[0]), _mm256_mul_ps(y, v[1])), _mm256_mul_ps(z, v[2]));
}
__attribute__((target("avx512f"), always_inline)) inline __m256 broadcast(const Vec3& v, int a) { return _mm256_set1_ps(v[a]); }
__attribute__((target("avx512f"), always_inline)) inline __m256i floor8(__m256 x) {
    const __m256i t = _mm256_cvttps_epi32(x);
    return _mm256_add_epi32(t, _mm256_castps_si256(_mm256_cmp_ps(x, _mm256_cvtepi32_ps(t), _CMP_LT_OS)));
}
__attribute__((target("avx512f"), always_inline)) inline void storeRect(int32_t rect[2][4][4], int row, __m256i v) {
    _mm_store_si128(reinterpret_cast<__m128i*>(rect[0][row]), _mm256_castsi256_si128(v));
    _mm_store_si128(reinterpret_cast<__m128i*>(rect[1][row]), _mm256_extracti128_si256(v, 1));
}
}  // namespace

__attribute__((target("avx512f"))) void CylinderTraversal::boxTests8(const Vec3& corner, const Vec3& lo, const Vec3& hi,
                                                                      uint32_t& may, uint32_t& sure, int32_t rect[2][4][4]) const {
    const __m256 offset[3] = {_mm256_setr_ps(0.f, 2.f, 0.f, 2.f, 0.f, 2.f, 0.f, 2.f), _mm256_setr_ps(0.f, 0.f, 2.f, 2.f, 0.f, 0.f, 2.f, 2.f),
                              _mm256_setr_ps(0.f, 0.f, 0.f, 0.f, 2.f, 2.f, 2.f, 2.f)};
    const __m256 halfOf = _mm256_set1_ps(0.5f), zero = _mm256_setzero_ps();
    __m256 w[3], absW[3], absN[3], nrm[3], aU[3], aV[3], absAU[3], absAV[3];
    __m256 d[3], half[3], valid = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    for (int a = 0; a < 3; ++a) {
        w[a] = broadcast(w_, a), absW[a] = broadcast(absW_, a), absN[a] = broadcast(absN_, a), nrm[a] = broadcast(n_, a);
        aU[a] = broadcast(aU_, a), aV[a] = broadcast(aV_, a), absAU[a] = broadcast(absAU_, a), absAV[a] = broadcast(absAV_, a);
        const __m256 octant = _mm256_add_ps(_mm256_set1_ps(corner[a]), offset[a]);
        const __m256 partLo = _mm256_max_ps(_mm256_sub_ps(octant, _mm256_set1_ps(kOctantEdge)), _mm256_set1_ps(lo[a]));
        const __m256 partHi = _mm256_min_ps(_mm256_add_ps(octant, _mm256_set1_ps(2.f + kOctantEdge)), _mm256_set1_ps(hi[a]));
        valid = _mm256_and_ps(valid, _mm256_cmp_ps(partLo, partHi, _CMP_LE_OS));
        d[a] = _mm256_sub_ps(_mm256_mul_ps(halfOf, _mm256_add_ps(partLo, partHi)), _mm256_set1_ps(o_[a]));
        half[a] = _mm256_mul_ps(halfOf, _mm256_sub_ps(partHi, partLo));
    }
    const __m256 along = dot8(w, d[0], d[1], d[2]), spreadW = dot8(absW, half[0], half[1], half[2]);
    const __m256 spreadN = dot8(absN, half[0], half[1], half[2]), dn = dot8(nrm, d[0], d[1], d[2]);
    const __m256 halfLength = _mm256_sqrt_ps(dot8(half, half[0], half[1], half[2]));
    const __m256 off2 = _mm256_sub_ps(dot8(d, d[0], d[1], d[2]), _mm256_mul_ps(along, along));
    const __m256 length = _mm256_set1_ps(L_);
    // boxMayBeReached.
    const __m256 slackM = _mm256_set1_ps(kBoxReachSlack), spreadM = _mm256_add_ps(spreadW, slackM);
    __m256 m = _mm256_and_ps(valid, _mm256_and_ps(_mm256_cmp_ps(_mm256_add_ps(along, spreadM), zero, _CMP_NLE_US),
                                                  _mm256_cmp_ps(_mm256_sub_ps(along, spreadM), length, _CMP_NGT_US)));
    if (hasNormal_) m = _mm256_and_ps(m, _mm256_cmp_ps(_mm256_add_ps(_mm256_add_ps(dn, spreadN), slackM), zero, _CMP_NLE_US));
    const __m256 reach = _mm256_add_ps(_mm256_add_ps(_mm256_set1_ps(radius_), halfLength), slackM);
    m = _mm256_and_ps(m, _mm256_cmp_ps(off2, _mm256_mul_ps(reach, reach), _CMP_LT_OS));
    may = uint32_t(_mm256_movemask_ps(m));
    // boxSurelyUnshadowed, up to its reading of the map.
    const __m256 size = _mm256_add_ps(_mm256_add_ps(_mm256_sqrt_ps(dot8(d, d[0], d[1], d[2])), halfLength), _mm256_set1_ps(1.f));
    const __m256 slack = _mm256_add_ps(_mm256_set1_ps(kSureSlack), _mm256_mul_ps(_mm256_set1_ps(kSureSlackPerSize), size));
    const __m256 slack2 = _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(kSureSlack2PerSize2), size), size);
    __m256 su = _mm256_and_ps(valid, _mm256_and_ps(_mm256_cmp_ps(_mm256_sub_ps(along, spreadW), slack, _CMP_GT_OS),
                                                   _mm256_cmp_ps(_mm256_add_ps(along, spreadW), _mm256_sub_ps(length, slack), _CMP_LE_OS)));
    if (hasNormal_) su = _mm256_and_ps(su, _mm256_cmp_ps(_mm256_sub_ps(dn, spreadN), slack, _CMP_GT_OS));
    const __m256 farthest =
        _mm256_add_ps(_mm256_add_ps(_mm256_sqrt_ps(_mm256_add_ps(_mm256_max_ps(off2, zero), slack2)), halfLength), slack);
    su = _mm256_and_ps(su, _mm256_cmp_ps(_mm256_add_ps(_mm256_mul_ps(farthest, farthest), slack2), _mm256_set1_ps(kernel2_), _CMP_LT_OS));
    sure = uint32_t(_mm256_movemask_ps(su)) & may;
    if (!sure) return;
    const __m256 u = dot8(aU, d[0], d[1], d[2]), du = _mm256_add_ps(dot8(absAU, half[0], half[1], half[2]), slack);
    const __m256 v = dot8(aV, d[0], d[1], d[2]), dv = _mm256_add_ps(dot8(absAV, half[0], half[1], half[2]), slack);
    const __m256i hu = _mm256_set1_epi32(halfU_), hv = _mm256_set1_epi32(halfV_);
    storeRect(rect, 0, _mm256_add_epi32(floor8(_mm256_sub_ps(_mm256_sub_ps(u, du), halfOf)), hu));
    storeRect(rect, 1, _mm256_add_epi32(floor8(_mm256_sub_ps(_mm256_add_ps(u, du), halfOf)), hu));
    storeRect(rect, 2, _mm256_add_epi32(floor8(_mm256_sub_ps(_mm256_sub_ps(v, dv), halfOf)), hv));
    storeRect(rect, 3, _mm256_add_epi32(floor8(_mm256_sub_ps(_mm256_add_ps(v, dv), halfOf)), hv));
}

// gatherSampleRange for sixteen samples at a time: reached lanes (reach()'s tests), their
// projections, first bilinear cells and slices, the shadowable map's first occluder slices read
// by a gather; the unshadowed samples' indices and the others' events written compressed, in
// sample order. A group with a reached sample whose block leaves the mask (none, by the mask's
// size) goes the scalar way.
__attribute__((target("avx512f"))) void CylinderTraversal::gatherSampleRange16(const StackEntry& e, uint32_t first,
                                                                                uint32_t last, bool surelyReached,
                                                                                size_t& events, size_t& listed) {
    size_t n = events, free = listed;
    const int layerLo = e.lo[N_], layerHi = int(e.hi[N_]) - 1;
    int sliceMin = sliceMin_, sliceMax = sliceMax_;
    __m512 origin[3], o[3], w[3], nrm[3], aU[3], aV[3];
    for (int a = 0; a < 3; ++a) {
        origin[a] = _mm512_set1_ps(g_.origin[a]), o[a] = _mm512_set1_ps(o_[a]), w[a] = _mm512_set1_ps(w_[a]);
        nrm[a] = _mm512_set1_ps(n_[a]), aU[a] = _mm512_set1_ps(aU_[a]), aV[a] = _mm512_set1_ps(aV_[a]);
    }
    const __m512 invVoxel = _mm512_set1_ps(invVoxel_), length = _mm512_set1_ps(L_), kernel2 = _mm512_set1_ps(kernel2_);
    const __m512 half = _mm512_set1_ps(0.5f);
    const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    const __m512i halfU = _mm512_set1_epi32(halfU_), halfV = _mm512_set1_epi32(halfV_);
    const __m512i sizeU = _mm512_set1_epi32(sizeU_), sizeV = _mm512_set1_epi32(sizeV_);
    const __m512i lo = _mm512_set1_epi32(layerLo), hi = _mm512_set1_epi32(layerHi);
    __m512i ab[3], c[3];
    for (int a = 0; a < 3; ++a) {
        ab[a] = _mm512_load_si512(kDeinterleave.ab[a]);
        c[a] = _mm512_load_si512(kDeinterleave.c[a]);
    }
    const uint16_t* shadow = shadow_;
    // The brick's voxel layers along N (at most kBrickSize) and their slices.
    const int layers = std::min(layerHi - layerLo + 1, kBrickSize);
    int layerSlice[kBrickSize], perLayer[kBrickSize] = {};
    for (int l = 0; l < layers; ++l) layerSlice[l] = sliceOf(layerLo + l);
    for (uint32_t i = first; i < last; i += 16) {
        const int count = int(std::min<uint32_t>(16u, last - i));
        const SampleLanes lanes = loadSamples16(&eye_.position[i].x, count, origin, invVoxel, o, ab, c);
        const __m512* p = lanes.p;
        const __m512* d = lanes.d;
        __mmask16 reached = firstLanes(count);
        if (!surelyReached && !(reached = reachLanes16(reached, d, w, length, kernel2, hasNormal_ ? nrm : nullptr))) continue;
        const __m512 u = dot16(aU, d[0], d[1], d[2]), v = dot16(aV, d[0], d[1], d[2]);
        const __m512i i0 = _mm512_add_epi32(floor16(_mm512_sub_ps(u, half)), halfU);
        const __m512i j0 = _mm512_add_epi32(floor16(_mm512_sub_ps(v, half)), halfV);
        const __mmask16 inMask = _mm512_mask_cmp_epu32_mask(_mm512_cmp_epu32_mask(i0, sizeU, _MM_CMPINT_LT), j0, sizeV,
                                                            _MM_CMPINT_LT);
        if (reached & ~inMask) {
            // A block at the mask's edge: the scalar tests, sample by sample.
            gatherSampleScalar(e, i, i + uint32_t(count), n, free, sliceMin, sliceMax);
            continue;
        }
        // The slices, and the shadowable map's first slice of each block (a 16-bit cell; the map
        // has one to spare past its end for the four-byte reads): a lane is shadowed past it.
        __m512i slice = _mm512_min_epi32(_mm512_max_epi32(floor16(p[N_]), lo), hi);
        if (!forward_) slice = _mm512_sub_epi32(_mm512_set1_epi32(dimN_ - 1), slice);
        const __m512i cell = _mm512_add_epi32(i0, _mm512_mullo_epi32(j0, sizeU));
        const __m512i first = _mm512_and_si512(_mm512_mask_i32gather_epi32(_mm512_setzero_si512(), reached, cell, shadow, 2),
                                               _mm512_set1_epi32(0xffff));
        const __mmask16 shadowed = _mm512_mask_cmp_epi32_mask(reached, slice, first, _MM_CMPINT_NLE);
        const __m512i index = _mm512_add_epi32(_mm512_set1_epi32(int(i)), lane);
        const __mmask16 unshadowed = reached & ~shadowed;
        // Compressed in a register and stored whole (the list has room to spare): a compressing
        // store to memory is slow on some CPUs.
        _mm512_storeu_si512(&s_.unshadowed[free], _mm512_maskz_compress_epi32(unshadowed, index));
        free += size_t(__builtin_popcount(unshadowed));
        if (!shadowed) continue;
        writeEvents16(shadowed, index, slice, u, v, &s_.samples[n]);
        // Per voxel layer of the brick, how many events it got (in registers: the same count
        // added to one cell sample by sample would wait on its own stores).
        for (int l = 0; l < layers; ++l)
            perLayer[l] += __builtin_popcount(_mm512_mask_cmp_epi32_mask(shadowed, slice, _mm512_set1_epi32(layerSlice[l]), _MM_CMPINT_EQ));
        n += size_t(__builtin_popcount(shadowed));
    }
    for (int l = 0; l < layers; ++l) {
        if (!perLayer[l]) continue;
        s_.sampleSlices[size_t(layerSlice[l])] += uint32_t(perLayer[l]);
        sliceMin = std::min(sliceMin, layerSlice[l]), sliceMax = std::max(sliceMax, layerSlice[l]);
    }
    sliceMin_ = sliceMin, sliceMax_ = sliceMax;
    st_.samplesReached += n + free - events - listed;
    st_.samplesTested += last - first;
    events = n, listed = free;
}

// read() for `count` (1…16) consecutive sample events, lane by lane the same operations in the
// same order (so the same values): the events' u and v turned to lanes, each block's two cell
// pairs read eight lanes at a time as 64-bit pairs, a cell's validity with its value
// (markInvalidCells). Writes the index and V of the events with V > 0, in event order, and returns
// how many.
__attribute__((target("avx512f"))) int CylinderTraversal::read16(const SampleEvent* ev, int count, uint32_t index[16],
                                                                   float vis[16]) const {
    static_assert(sizeof(SampleEvent) == 16, "an event is four floats: index, slice, u, v");
    const float* f = reinterpret_cast<const float*>(ev);
    const __m512 e0 = _mm512_maskz_loadu_ps(firstLanes(4 * count), f), e1 = _mm512_maskz_loadu_ps(firstLanes(4 * count - 16), f + 16);
    const __m512 e2 = _mm512_maskz_loadu_ps(firstLanes(4 * count - 32), f + 32), e3 = _mm512_maskz_loadu_ps(firstLanes(4 * count - 48), f + 48);
    // Lanes 0-7: the u of events 0-7 (float 4l + 2 of the pair of vectors), lanes 8-15 their v.
    const __m512i uvIndex = _mm512_setr_epi32(2, 6, 10, 14, 18, 22, 26, 30, 3, 7, 11, 15, 19, 23, 27, 31);
    const __m512 lowHalf = _mm512_permutex2var_ps(e0, uvIndex, e1), highHalf = _mm512_permutex2var_ps(e2, uvIndex, e3);
    const __m512 u = _mm512_shuffle_f32x4(lowHalf, highHalf, _MM_SHUFFLE(1, 0, 1, 0));
    const __m512 v = _mm512_shuffle_f32x4(lowHalf, highHalf, _MM_SHUFFLE(3, 2, 3, 2));
    const __m512 half = _mm512_set1_ps(0.5f), one = _mm512_set1_ps(1.f), x = _mm512_sub_ps(u, half), y = _mm512_sub_ps(v, half);
    const __m512i ix = floor16(x), iy = floor16(y);
    const __m512 fx = _mm512_sub_ps(x, _mm512_cvtepi32_ps(ix)), fy = _mm512_sub_ps(y, _mm512_cvtepi32_ps(iy));
    const __m512i i0 = _mm512_add_epi32(ix, _mm512_set1_epi32(halfU_)), j0 = _mm512_add_epi32(iy, _mm512_set1_epi32(halfV_));
    const __mmask16 active = firstLanes(count);
    const __mmask16 inside = _mm512_mask_cmp_epu32_mask(_mm512_cmp_epu32_mask(i0, _mm512_set1_epi32(sizeU_ - 1), _MM_CMPINT_LT), j0,
                                                        _mm512_set1_epi32(sizeV_ - 1), _MM_CMPINT_LT);
    if (active & ~inside) {
        int lit = 0;  // a block at the mask's edge (none, by its size)
        for (int k = 0; k < count; ++k) {
            const float v = read(ev[k]);
            if (v > 0.f) index[lit] = ev[k].index, vis[lit++] = v;
        }
        return lit;
    }
    // 64-bit reads, eight lanes at a time: the cells (c, c + 1) of rows j0 and j0 + 1, then the
    // pairs split into lanes. An invalid cell holds kInvalidCell: its weight is made 0.
    const __m512i cell = _mm512_add_epi32(i0, _mm512_mullo_epi32(j0, _mm512_set1_epi32(sizeU_)));
    const __m512i nextRow = _mm512_add_epi32(cell, _mm512_set1_epi32(sizeU_));
    const double* sweep = reinterpret_cast<const double*>(s_.sweep.data());
    __m512i c00, c10, c01, c11;
    gatherPairs(active, cell, sweep, c00, c10);
    gatherPairs(active, nextRow, sweep, c01, c11);
    const __m512 gx = _mm512_sub_ps(one, fx), gy = _mm512_sub_ps(one, fy);
    const __m512 w0 = validWeight(c00, _mm512_mul_ps(gx, gy)), w1 = validWeight(c10, _mm512_mul_ps(fx, gy));
    const __m512 w2 = validWeight(c01, _mm512_mul_ps(gx, fy)), w3 = validWeight(c11, _mm512_mul_ps(fx, fy));
    // (t0 + t2) + (t1 + t3), as read() adds its lanes.
    const __m512 num = _mm512_add_ps(_mm512_add_ps(cellTerm(w0, c00), cellTerm(w2, c01)), _mm512_add_ps(cellTerm(w1, c10), cellTerm(w3, c11)));
    const __m512 den = _mm512_add_ps(_mm512_add_ps(w0, w2), _mm512_add_ps(w1, w3));
    const __mmask16 shadowed = _mm512_cmp_ps_mask(num, _mm512_setzero_ps(), _CMP_GT_OS);
    const __m512 seen = _mm512_mask_sub_ps(one, shadowed, one, _mm512_mask_div_ps(one, shadowed, num, den));
    // The events' indices (float 4l of the pair of vectors, lanes 0-7 of each permute), and
    // the lanes that see light, compressed.
    const __m512i indexOf = _mm512_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28, 0, 4, 8, 12, 16, 20, 24, 28);
    const __m512i lowIndex = _mm512_permutex2var_epi32(_mm512_castps_si512(e0), indexOf, _mm512_castps_si512(e1));
    const __m512i highIndex = _mm512_permutex2var_epi32(_mm512_castps_si512(e2), indexOf, _mm512_castps_si512(e3));
    const __mmask16 lit = _mm512_mask_cmp_ps_mask(active, seen, _mm512_setzero_ps(), _CMP_GT_OS);
    _mm512_store_si512(index, _mm512_maskz_compress_epi32(lit, _mm512_shuffle_i32x4(lowIndex, highIndex, _MM_SHUFFLE(1, 0, 1, 0))));
    _mm512_store_ps(vis, _mm512_maskz_compress_ps(lit, seen));
    return __builtin_popcount(lit);
}

#endif

}  // namespace rs
