// The splat's writes into a thread's fixed-point film (splat.cpp): a contribution is added as
// three 64-bit integers (FixedFilm::kScale, 2^-32 resolution), so any order of the adds gives the
// same sums; those whose rule 2 needs Embree wait in a packet of RayAccel::kPacket.
#pragma once

#include <cstdint>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "output/film.h"
#include "scene/accel.h"

namespace rs {

// A non-negative value in the film's fixed point, rounded half up, saturated.
inline int64_t fixedOf(float v) {
    const double x = double(v) * FixedFilm::kScale;
    return x < 9.0e18 ? int64_t(x + 0.5) : int64_t(9.0e18);
}

// Adds c (non-negative, finite) to a pixel's three fixed-point sums.
inline void addFixed(int64_t* px, const Vec3& c) {
#if defined(__SSE2__)
    // fixedOf two lanes at a time where every value is below 2^51: there x + 0.5 is the same
    // double, and its truncation is the integer part of (x + 0.5) + 2^52 (round to nearest),
    // less one where that rounded up.
    const __m128d scale = _mm_set1_pd(FixedFilm::kScale), limit = _mm_set1_pd(2251799813685248.0);  // 2^51
    const __m128d xy = _mm_mul_pd(_mm_cvtps_pd(_mm_setr_ps(c.x, c.y, 0.f, 0.f)), scale);
    const __m128d z = _mm_mul_pd(_mm_cvtps_pd(_mm_set_ss(c.z)), scale);
    if (_mm_movemask_pd(_mm_and_pd(_mm_cmplt_pd(xy, limit), _mm_cmplt_pd(z, limit))) == 3) {
        auto truncHalfUp = [](__m128d x) {
            const __m128d big = _mm_set1_pd(4503599627370496.0);  // 2^52
            const __m128d y = _mm_add_pd(x, _mm_set1_pd(0.5)), r = _mm_add_pd(y, big);
            const __m128i n = _mm_sub_epi64(_mm_castpd_si128(r), _mm_castpd_si128(big));
            return _mm_add_epi64(n, _mm_castpd_si128(_mm_cmpgt_pd(_mm_sub_pd(r, big), y)));
        };
        __m128i* pxy = reinterpret_cast<__m128i*>(px);
        _mm_storeu_si128(pxy, _mm_add_epi64(_mm_loadu_si128(pxy), truncHalfUp(xy)));
        px[2] += _mm_cvtsi128_si64(truncHalfUp(z));
        return;
    }
#endif
    px[0] += fixedOf(c.x);
    px[1] += fixedOf(c.y);
    px[2] += fixedOf(c.z);
}

// Contributions waiting for rule 2, which is asked a packet at a time (Receivers::hidden, for
// splat.h's SegmentReceivers); those whose sample turns out hidden are dropped, the others added
// to the thread's film buffer, counted in Stats (SplatStats).
template <class Receivers, class Stats>
class PendingContributions {
public:
    PendingContributions(const Receivers& receivers, Stats& stats) : receivers_(receivers), stats_(stats) {}
    ~PendingContributions() { flush(); }

    void add(const Vec3& lifted, int64_t* pixel, const Vec3& c) {
        lifted_[count_] = lifted, pixel_[count_] = pixel, c_[count_] = c;
        if (++count_ == RayAccel::kPacket) flush();
    }
    void flush() {
        if (count_ == 0) return;
        const uint32_t hidden = receivers_.hidden(lifted_, count_);
        stats_.visibilityRays += uint64_t(count_);
        for (int i = 0; i < count_; ++i) {
            if (hidden >> i & 1u) {
                ++stats_.refusedHidden;
                continue;
            }
            addFixed(pixel_[i], c_[i]);
            ++stats_.contributions;
        }
        count_ = 0;
    }
private:
    const Receivers& receivers_;
    Stats& stats_;
    int count_ = 0;
    Vec3 lifted_[RayAccel::kPacket], c_[RayAccel::kPacket];
    int64_t* pixel_[RayAccel::kPacket];
};

}  // namespace rs
