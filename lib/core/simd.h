// The instruction set of the wide steps, chosen once for the process, and the four-lane
// (SSE2) helpers shared by the traversal and the splat.
#pragma once

// The build has the sixteen-lane (AVX-512) steps of the occlusion tree's traversal, compiled for
// that target function by function (occlusion/kdtree_traverse_avx512.cpp) and run where the CPU
// has it.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define RS_TRAVERSE_AVX512 1
#else
#define RS_TRAVERSE_AVX512 0
#endif

namespace rs {

// The instruction sets the traversal's steps come in; the value is their lane count. Both give
// the same answers, bit for bit.
enum class Isa { Sse2 = 4, Avx512 = 16 };
const char* isaName(Isa isa);  // "sse2", "avx512"
// The one the traversal uses: the widest this CPU runs, unless RAYSPLAT_SIMD names another
// (sse2 or avx512). Decided on the first call; checkSimdEnvironment() refuses an unknown name.
Isa traversalIsa();
// Throws Error(Config) naming the valid values when RAYSPLAT_SIMD is set to anything else, or
// to an instruction set this CPU lacks.
void checkSimdEnvironment();
// Changes the choice for the whole process (tests comparing the paths); false, and no change,
// when the CPU lacks `isa`. ScopedTraversalIsa restores the previous choice however its scope ends.
bool setTraversalIsa(Isa isa);
class ScopedTraversalIsa {
public:
    explicit ScopedTraversalIsa(Isa isa) : before_(traversalIsa()), ok_(setTraversalIsa(isa)) {}
    ~ScopedTraversalIsa() { setTraversalIsa(before_); }
    ScopedTraversalIsa(const ScopedTraversalIsa&) = delete;
    ScopedTraversalIsa& operator=(const ScopedTraversalIsa&) = delete;
    bool ok() const { return ok_; }  // the CPU runs it

private:
    Isa before_;
    bool ok_;
};

}  // namespace rs

#if defined(__SSE2__)
#include <immintrin.h>

namespace rs {

// v·(x, y, z) lane by lane, as (x·v₀ + y·v₁) + z·v₂: glm::dot's order, so each lane gives the
// scalar dot's value to the bit.
inline __m128 dot4(const __m128 v[3], __m128 x, __m128 y, __m128 z) {
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(x, v[0]), _mm_mul_ps(y, v[1])), _mm_mul_ps(z, v[2]));
}

// floorToInt lane by lane: truncate, then step down where that went up.
inline __m128i floorToInt4(__m128 x) {
    const __m128i t = _mm_cvttps_epi32(x);
    return _mm_add_epi32(t, _mm_castps_si128(_mm_cmplt_ps(x, _mm_cvtepi32_ps(t))));
}

}  // namespace rs
#endif
