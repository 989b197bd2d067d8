// The eye samples and the receivers a pass's photons land on, and the splat onto them (targets.h).
#include "splat/targets.h"

#include <algorithm>

#include "ranks.h"

namespace rs {

PassTargets::PassTargets(const RayAccel& accel, const OcclusionGrid& grid, EyeSamples& samples, int width, int height,
                         float spacing, ThreadPool& pool, Reporter& reporter, Ranks& ranks, OcclusionTreeStats* treeStats)
    : accel_(accel), samples_(samples), pool_(pool), reporter_(reporter), ranks_(ranks) {
    if (spacing > 0.f) {  // chosen from the samples in pixel order, before the tree reorders them
        receivers_ = chooseReceivers(samples, width, height, spacing, pool);
        receiverIndex_ = CylinderIndex(receivers_.samples.position);
        sparse_ = true;
    }
    tree_ = buildOcclusionTree(grid, samples, pool, treeStats);
}

uint64_t PassTargets::splat(const PhotonMap& photons, const SplatSettings& settings, FixedFilm& part, SplatStats* stats,
                            CoverageStats* coverage, const std::function<bool()>& timeUp, std::vector<int64_t>* sums) const {
    std::vector<int64_t> own;
    std::vector<int64_t>& slots = sums ? *sums : own;  // the receivers' irradiance, slot × RGB
    slots.resize(sparse_ ? receivers_.slots() * 3 : 0, 0);
    const size_t n = photons.rays.size();
    uint64_t covered = UINT64_MAX;
    for (size_t begin = 0; begin < n;) {
        size_t end = timeUp ? std::min(n, begin + std::max(kPortion, n / kPortions)) : n;
        while (end < n && photons.rays[end].path == photons.rays[end - 1].path) ++end;  // whole paths
        splatPortion(photons, begin, end, settings, part, slots, stats, coverage);
        begin = end;
        if (begin < n && timeUp()) {
            covered = photons.rays[begin].path;
            break;
        }
    }
    // Without indirect photons (the first pass's others, beside its probe) the slots hold nothing.
    const bool landsOnReceivers = std::any_of(photons.rays.begin(), photons.rays.end(),
                                              [](const PhotonRay& r) { return r.cls == kPhotonIndirect; });
    if (!sums && landsOnReceivers) gather({&slots}, {&part}, settings);
    return covered;
}

double PassTargets::gatherSeconds() const { return sparse_ ? rs::gatherSeconds(receivers_, samples_, pool_) : 0.0; }

void PassTargets::land(const PhotonMap& photons, const SplatSettings& settings, FixedFilm& part, std::vector<int64_t>& slots,
                       SplatStats* stats, CoverageStats* coverage) const {
    slots.assign(sparse_ ? receivers_.slots() * 3 : 0, 0);
    splatPortion(photons, 0, photons.rays.size(), settings, part, slots, stats, coverage);
}

void PassTargets::gather(const std::vector<std::vector<int64_t>*>& slots, const std::vector<FixedFilm*>& parts,
                         const SplatSettings& settings) const {
    if (!sparse_) return;
    if (settings.shares > 1)
        for (std::vector<int64_t>* s : slots) ranks_.sumAtRoot(*s);
    if (settings.share != 0) return;
    std::vector<const std::vector<int64_t>*> sums(slots.begin(), slots.end());
    std::vector<std::vector<int64_t>*> pixels;
    for (FixedFilm* p : parts) pixels.push_back(&p->buffers[kIndirect]);
    gatherIrradiance(receivers_, samples_, sums, FixedFilm::kScale, pixels, pool_);
}

// Photons [begin, end): the indirect ones onto the receivers' `slots`, the others onto `part`.
void PassTargets::splatPortion(const PhotonMap& photons, size_t begin, size_t end, const SplatSettings& settings,
                               FixedFilm& part, std::vector<int64_t>& slots, SplatStats* stats, CoverageStats* coverage) const {
    PhotonMap indirect, others;
    for (size_t i = begin; i < end; ++i) {
        PhotonMap& to = sparse_ && photons.rays[i].cls == kPhotonIndirect ? indirect : others;
        to.rays.push_back(photons.rays[i]);
        if (!photons.edges.empty()) to.edges.push_back(photons.edges[i]);
    }
    if (!others.rays.empty()) splatPhotons(accel_, tree_, samples_, others, settings, part, pool_, reporter_, stats, coverage);
    if (indirect.rays.empty()) return;
    SplatSettings sparse = settings;
    // A few rays a photon: finding the triangles near its cylinder cost more than the rays they
    // spared (the staircase interior's splat 1.5 → 1.05 s without them).
    sparse.visibilityPlanes = false;
    FixedFilm receivers;  // the slots as a film of one row, as splatPhotons writes
    receivers.width = int(receivers_.slots()), receivers.height = 1;
    receivers.buffers[kIndirect].swap(slots);
    sparse.index = &receiverIndex_;
    splatPhotons(accel_, tree_, receivers_.samples, indirect, sparse, receivers, pool_, reporter_, stats, coverage);
    receivers.buffers[kIndirect].swap(slots);
}

}  // namespace rs
