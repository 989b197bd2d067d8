// The photon tracer's quasi-Monte Carlo sequence (docs/design.md §7): Halton with random digit
// permutations (one per dimension and digit, drawn from the seed), so that path n's numbers
// are a pure function of (seed, n, dimension). Dimensions past the table fall back to hashed
// random numbers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace rs {

class ScrambledHalton {
public:
    ScrambledHalton(uint64_t seed, int dimensions);
    int dimensions() const { return int(bases_.size()); }
    float sample(uint64_t index, int dim) const;
    // The same number, one permuted digit at a time: what sample()'s shortcuts (bit reversal
    // for base 2, two digits a step up to kMaxPairBase) are checked against.
    float sampleByDigits(uint64_t index, int dim) const;

private:
    uint64_t sampleDigits(uint64_t index, int dim) const;  // the reversed digits, one at a time

    uint64_t seed_;
    std::vector<int> bases_, digits_;
    std::vector<double> scales_;      // bases_[d]^−digits_[d]
    std::vector<size_t> offset_;      // into perms_, per dimension
    std::vector<uint16_t> perms_;     // digits_[d] permutations of bases_[d] digits each
    // Per dimension, per number of digits m (0…digits): what the permuted zero digits m… add
    // to the reversed digits (zeros_), and the factor that shifts m reversed digits past them
    // (powers_, bases_[d]^(digits − m)); indexed from offsetM_[d].
    std::vector<uint64_t> zeros_, powers_;
    std::vector<size_t> offsetM_;
    // The same integers, faster. Base 2: each digit's permutation keeps it or flips it, so the
    // reversed digits are the index's bits reversed, XOR the flips. Bases 3 to kMaxPairBase: two
    // digits at a time, each pair's permuted digits at their places in pairs_ (pair j's b² values
    // from offsetPairs_[d] + j·b²).
    static constexpr int kMaxPairBase = 31;
    uint64_t flips2_ = 0;
    std::vector<uint64_t> pairs_;
    std::vector<size_t> offsetPairs_;
};

}  // namespace rs
