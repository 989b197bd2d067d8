#include "core/qmc.h"

#include <algorithm>
#include <cmath>

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
    }
}

float ScrambledHalton::sample(uint64_t index, int dim) const {
    if (dim >= dimensions()) return toUnitFloat(uint32_t(hashKey(seed_, Stage::Photon, index, uint64_t(dim)) >> 32));
    const uint64_t b = uint64_t(bases_[dim]);
    const uint16_t* perm = &perms_[offset_[dim]];
    uint64_t reversed = 0;
    double scale = 1.0;
    for (int k = 0; k < digits_[dim]; ++k) {
        uint64_t next = index / b;
        uint64_t digit = index - next * b;
        reversed = reversed * b + perm[size_t(k) * b + digit];
        scale /= double(b);
        index = next;
    }
    return std::min(float(double(reversed) * scale), 0x1.fffffep-1f);
}

}  // namespace rs
