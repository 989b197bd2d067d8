// What a pass's photons land on (docs/design.md §8): every eye sample, through the occlusion tree
// over them, for direct and caustic photons; with sparse receivers (irradiance.h) the indirect
// photons on the receivers, found through an index of their own (cylinder_index.h), gathered back
// to the eye samples.
//
// Takes:   the pass's eye samples in pixel order (the tree reorders them), the occlusion grid,
//          the receivers' spacing (0: none).
// Splats:  a photon map, or the part of it a time limit leaves (whole paths, in path order), into
//          a film's photon layers. In a pass shared by MPI ranks the receivers' sums meet at rank 0
//          before the gather, so the image is a single process's to the bit.
#pragma once

#include <cstdint>
#include <functional>

#include "occlusion/kdtree.h"
#include "splat/irradiance.h"
#include "splat/splat.h"

namespace rs {

class Ranks;

class PassTargets {
public:
    PassTargets(const RayAccel& accel, const OcclusionGrid& grid, EyeSamples& samples, int width, int height, float spacing,
                ThreadPool& pool, Reporter& reporter, Ranks& ranks, OcclusionTreeStats* treeStats = nullptr);

    const OcclusionTree& tree() const { return tree_; }
    // The samples the indirect photons land on.
    size_t receivers() const { return sparse_ ? receivers_.slots() : samples_.size(); }

    // Adds `photons`' light (this rank's share, settings.share of settings.shares) to `part`'s
    // photon layers. With `timeUp`, in portions of whole paths (a sixteenth of the photons, at
    // least 4096), until it says the time is up (after a portion, so at least one). Returns the
    // paths whose photons were all splatted, [0, P) of the pass: UINT64_MAX for all of them.
    // With `sums`, the indirect photons' receivers' sums are added there and not gathered: a
    // pass's photon rounds are gathered once (gather()), which is the sum of their gathers.
    uint64_t splat(const PhotonMap& photons, const SplatSettings& settings, FixedFilm& part, SplatStats* stats,
                   CoverageStats* coverage, const std::function<bool()>& timeUp = nullptr,
                   std::vector<int64_t>* sums = nullptr) const;

    static constexpr size_t kPortions = 16, kPortion = 4096;

    // The seconds a gather of the receivers takes (gatherSeconds in irradiance.h; 0 without
    // sparse receivers): under a time limit the splat stops that long before the deadline.
    double gatherSeconds() const;

    // splat() in two steps, for several photon maps whose receivers are searched once: land()
    // adds `photons`' light to `part`'s photon layers, the indirect photons' on sparse receivers
    // to `slots` (the receivers' sums, sized here); gather() sums each `slots` at rank 0 in a
    // shared pass and adds it to its `parts` as splat() would have.
    void land(const PhotonMap& photons, const SplatSettings& settings, FixedFilm& part, std::vector<int64_t>& slots,
              SplatStats* stats, CoverageStats* coverage) const;
    void gather(const std::vector<std::vector<int64_t>*>& slots, const std::vector<FixedFilm*>& parts,
                const SplatSettings& settings) const;

private:
    void splatPortion(const PhotonMap& photons, size_t begin, size_t end, const SplatSettings& settings, FixedFilm& part,
                      std::vector<int64_t>& slots, SplatStats* stats, CoverageStats* coverage) const;

    const RayAccel& accel_;
    EyeSamples& samples_;
    ThreadPool& pool_;
    Reporter& reporter_;
    Ranks& ranks_;
    OcclusionTree tree_;
    bool sparse_ = false;
    IrradianceReceivers receivers_;
    CylinderIndex receiverIndex_;
};

}  // namespace rs
