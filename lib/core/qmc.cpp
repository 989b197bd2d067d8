#include "core/qmc.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "core/sampling.h"

namespace rs {

ScrambledHalton::ScrambledHalton(uint64_t seed, int dimensions) : seed_(seed) {
    // The first `dimensions` primes.
    for (int n = 2; int(bases_.size()) < dimensions; ++n) {
        bool prime = true;
        for (int p : bases_) {
            if (p * p > n) break;
            if (n % p == 0) { prime = false; break; }
        }
        if (prime) bases_.push_back(n);
    }
    for (int d = 0; d < dimensions; ++d) {
        int b = bases_[d];
        // As many digits as keep base^digits below 2^62 (exact integer reversal).
        int nd = int(std::floor(62.0 / std::log2(double(b))));
        digits_.push_back(nd);
        double scale = 1.0;  // b^−nd, divided down as the digits were once: the same double
        for (int k = 0; k < nd; ++k) scale /= double(b);
        scales_.push_back(scale);
        offset_.push_back(perms_.size());
        for (int k = 0; k < nd; ++k) {
            size_t start = perms_.size();
            for (int i = 0; i < b; ++i) perms_.push_back(uint16_t(i));
            uint64_t h = hashKey(seed, Stage::Photon, uint64_t(d) << 8 | uint64_t(k), 0x51);
            for (int i = b - 1; i > 0; --i) {  // Fisher–Yates from a hashed stream
                h = mix64(h + 0x9e3779b97f4a7c15ull);
                std::swap(perms_[start + i], perms_[start + (h % uint64_t(i + 1))]);
            }
        }
        // Once the index's digits run out, digits m… are all zero: their permuted values add a
        // constant, zeros[m] = Σ_{k ≥ m} perm_k(0)·b^(nd−1−k), after m digits shifted by b^(nd−m).
        offsetM_.push_back(zeros_.size());
        std::vector<uint64_t> zeros(size_t(nd) + 1, 0), powers(size_t(nd) + 1, 1);
        for (int m = nd - 1; m >= 0; --m) {
            powers[size_t(m)] = powers[size_t(m) + 1] * uint64_t(b);
            zeros[size_t(m)] = zeros[size_t(m) + 1] + uint64_t(perms_[offset_.back() + size_t(m) * size_t(b)]) * powers[size_t(m) + 1];
        }
        zeros_.insert(zeros_.end(), zeros.begin(), zeros.end());
        powers_.insert(powers_.end(), powers.begin(), powers.end());
        const uint16_t* perm = &perms_[offset_.back()];
        if (b == 2)
            for (int k = 0; k < nd; ++k) flips2_ |= uint64_t(perm[2 * k]) << (nd - 1 - k);
        offsetPairs_.push_back(pairs_.size());
        if (b == 2 || b > kMaxPairBase) continue;
        for (int k = 0; k < nd; k += 2)
            for (int d1 = 0; d1 < b; ++d1)
                for (int d0 = 0; d0 < b; ++d0)
                    pairs_.push_back(uint64_t(perm[size_t(k) * size_t(b) + size_t(d0)]) * powers[size_t(k) + 1] +
                                     (k + 1 < nd ? uint64_t(perm[size_t(k + 1) * size_t(b) + size_t(d1)]) * powers[size_t(k) + 2] : 0));
    }
}

namespace {

// The scrambled radical inverse's digits: `digits` permuted digits of index in base b, most
// significant last. Base is a std::integral_constant for the small primes, so that the
// compiler divides by multiplying, or a plain uint64_t.
// Digits past the index's own are zeros, whose permuted values are a constant per count:
// (the same integer as reversing all `digits`).
template <class Base>
uint64_t reverseDigits(Base base, uint64_t index, int digits, const uint16_t* perm, const uint64_t* zeros,
                       const uint64_t* powers) {
    const uint64_t b = base;
    uint64_t reversed = 0;
    int k = 0;
    for (; k < digits && index != 0; ++k) {
        const uint64_t next = index / b;
        reversed = reversed * b + perm[size_t(k) * b + (index - next * b)];
        index = next;
    }
    return reversed * powers[k] + zeros[k];
}

template <uint64_t B>
using Prime = std::integral_constant<uint64_t, B>;

// The same integer as reverseDigits, two digits a step: `pairs` holds each pair's permuted
// digits at their places, `zeros` the permuted zeros past the index's own digits.
template <class Base>
uint64_t reversePairs(Base base, uint64_t index, int digits, const uint64_t* pairs, const uint64_t* zeros) {
    const uint64_t b = base, bb = b * b;
    uint64_t sum = 0;
    int k = 0;
    for (; k < digits && index != 0; k += 2) {
        const uint64_t next = index / bb;
        sum += pairs[size_t(k / 2) * bb + (index - next * bb)];
        index = next;
    }
    return sum + zeros[std::min(k, digits)];
}

// f(Prime<b>()) for the primes up to 31, so that f's divisions by b are multiplications; else f(b).
template <class F>
uint64_t withBase(uint64_t b, F&& f) {
    switch (b) {
        case 2: return f(Prime<2>());
        case 3: return f(Prime<3>());
        case 5: return f(Prime<5>());
        case 7: return f(Prime<7>());
        case 11: return f(Prime<11>());
        case 13: return f(Prime<13>());
        case 17: return f(Prime<17>());
        case 19: return f(Prime<19>());
        case 23: return f(Prime<23>());
        case 29: return f(Prime<29>());
        case 31: return f(Prime<31>());
        default: return f(b);
    }
}

uint64_t reverseBits(uint64_t x) {
    x = (x >> 1 & 0x5555555555555555ull) | (x & 0x5555555555555555ull) << 1;
    x = (x >> 2 & 0x3333333333333333ull) | (x & 0x3333333333333333ull) << 2;
    x = (x >> 4 & 0x0f0f0f0f0f0f0f0full) | (x & 0x0f0f0f0f0f0f0f0full) << 4;
    return __builtin_bswap64(x);
}

}  // namespace

float ScrambledHalton::sample(uint64_t index, int dim) const {
    if (dim >= dimensions()) return sampleByDigits(index, dim);
    const int b = bases_[dim], digits = digits_[dim];
    uint64_t reversed;
    if (b == 2)  // 62 digits: the index's bits 0…61 reversed
        reversed = (reverseBits(index) >> (64 - digits)) ^ flips2_;
    else if (b <= kMaxPairBase)
        reversed = withBase(uint64_t(b), [&](auto base) {
            return reversePairs(base, index, digits, &pairs_[offsetPairs_[dim]], &zeros_[offsetM_[dim]]);
        });
    else
        reversed = sampleDigits(index, dim);
    return std::min(float(double(reversed) * scales_[dim]), 0x1.fffffep-1f);
}

float ScrambledHalton::sampleByDigits(uint64_t index, int dim) const {
    if (dim >= dimensions()) return toUnitFloat(uint32_t(hashKey(seed_, Stage::Photon, index, uint64_t(dim)) >> 32));
    return std::min(float(double(sampleDigits(index, dim)) * scales_[dim]), 0x1.fffffep-1f);
}

uint64_t ScrambledHalton::sampleDigits(uint64_t index, int dim) const {
    return withBase(uint64_t(bases_[dim]), [&](auto base) {
        return reverseDigits(base, index, digits_[dim], &perms_[offset_[dim]], &zeros_[offsetM_[dim]], &powers_[offsetM_[dim]]);
    });
}

}  // namespace rs
