// Four-lane (SSE2) helpers shared by the traversal and the splat.
#pragma once

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
