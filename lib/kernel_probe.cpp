// The first pass's probe of the indirect kernels' scale (kernel_probe.h): its halves, the
// choice at rank 0, and where a replayed ray of that pass was splatted.
#include "kernel_probe.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/sampling.h"

#include "splat/targets.h"

namespace rs {

namespace {

constexpr int kProbeLayers = kCaustic + 1;  // the layers a splat writes: direct, indirect, caustic

// Photons [first, last) of `photons`, in path order.
PhotonMap slice(const PhotonMap& photons, size_t first, size_t last) {
    PhotonMap out = photons;
    out.rays.assign(photons.rays.begin() + first, photons.rays.begin() + last);
    if (!photons.edges.empty()) out.edges.assign(photons.edges.begin() + first, photons.edges.begin() + last);
    return out;
}

// The probe's halves of `photons`: its paths, each to one half by a hash of its number. Halves of
// the path order would be two runs of the pass's Halton points, whose errors are not
// independent, and S (kernel_scale.h) assumes they are.
std::array<PhotonMap, 2> halvesOf(const PhotonMap& photons, uint64_t seed) {
    std::array<PhotonMap, 2> halves{photons, photons};
    for (PhotonMap& h : halves) h.rays.clear(), h.edges.clear();
    for (const PhotonRay& ray : photons.rays) halves[hashKey(seed, Stage::Probe, ray.path) & 1u].rays.push_back(ray);
    return halves;
}

// The scale at which the first pass keeps its probed photons' light, for the scale m chosen.
float keptProbeScale(float m) { return m < std::sqrt(0.5f) ? 0.5f : 1.f; }

// The photon rounds' noises (kernel_scale.h) from the first pass: the photons' V at the scale
// chosen, and the direct film's, weighted by the pass's light μ as V is (1/(μ² + 0.01)).
PhotonRoundsPlan roundsNoise(const EyePass& eye, const std::vector<float>& light, double photonNoise, Stats& stats) {
    PhotonRoundsPlan plan;
    for (size_t i = 0; i < light.size(); ++i)
        plan.filmNoise += double(eye.filmNoise[i / 3][int(i % 3)]) / (double(light[i]) * light[i] + 0.01);
    plan.photonNoise = photonNoise;
    stats.setCount("photon_rounds_film_noise", plan.filmNoise);
    stats.setCount("photon_rounds_photon_noise", plan.photonNoise);
    return plan;
}

}  // namespace

size_t KernelScaleProbeStep::landHalves(const PhotonMap& indirect, size_t first, size_t last, const PhotonSettings& ps,
                                        FixedFilm parts[4], std::vector<int64_t> slots[4], double seconds[2],
                                        const std::function<bool()>& timeUp) {
    std::vector<int64_t> portionSlots;
    for (int j = 0; j < 4; ++j) {
        parts[j].width = c_.width, parts[j].height = c_.height;
        parts[j].buffers[kIndirect].assign(values_, 0);
    }
    seconds[0] = seconds[1] = 0.0;
    const size_t portion = std::max(PassTargets::kPortion, (last - first) / PassTargets::kPortions);
    size_t end = first;
    do {  // at least once: an empty share still sizes the slots the gather reads
        size_t next = timeUp ? std::min(last, end + portion) : last;
        while (next < last && indirect.rays[next].path == indirect.rays[next - 1].path) ++next;  // whole paths
        for (int f = 0; f < 2; ++f) {
            Timer t;
            const PhotonMap scaled = scaledKernels(c_.scene, slice(indirect, end, next), kPhotonIndirect, f ? 0.5f : 1.f, ps);
            const std::array<PhotonMap, 2> halves = halvesOf(scaled, c_.cfg.seed);
            for (int h = 0; h < 2; ++h) {
                std::vector<int64_t>& to = slots[2 * f + h];
                targets_.land(halves[h], splat_, parts[2 * f + h], portionSlots, f == 0 ? &totals_.splat : nullptr,
                              f == 0 ? &totals_.coverage : nullptr);
                if (to.empty()) to.swap(portionSlots);
                else
                    for (size_t i = 0; i < to.size(); ++i) FixedFilm::addSaturating(to[i], portionSlots[i]);
            }
            seconds[f] += t.seconds();
        }
        end = next;
    } while (end < last && !(timeUp && timeUp()));
    return end;
}

void KernelScaleProbeStep::gatherHalves(FixedFilm parts[4], std::vector<int64_t> slots[4], std::vector<int64_t> mine[2],
                                        double& gather) {
    // The receivers searched once for B, C and D; A's gather alone is timed as a pass's.
    Timer gathering;
    targets_.gather({&slots[0]}, {&parts[0]}, splat_);
    gather = gathering.seconds();
    targets_.gather({&slots[1], &slots[2], &slots[3]}, {&parts[1], &parts[2], &parts[3]}, splat_);
    for (int j = 0; j < 4; ++j) addMine(parts[j], mine[j / 2]);
}

void KernelScaleProbeStep::addMine(FixedFilm& part, std::vector<int64_t>& mine) {
    std::vector<int64_t>& light = part.buffers[kIndirect];
    mine.resize(values_);
    for (size_t i = 0; i < values_; ++i) mine[i] += light[i];
    c_.ranks.sumAtRoot(light);
}

float KernelScaleProbeStep::run(const PhotonMap& indirect, const PhotonSettings& ps, FixedFilm& sum, const Timer& whole,
                                double other, const SplatTime& time, uint64_t& covered) {
    const std::function<bool()> timeUp = time.timeUp();
    const size_t n = indirect.rays.size(), share = n / KernelScaleProbe::kShare;
    FixedFilm parts[4];              // A, B, C, D: their indirect layer only
    std::vector<int64_t> slots[4];   // their receivers' sums
    std::vector<int64_t> mine[2];    // this rank's light of the probed photons at 1 and at ½
    double seconds[2], gather = 0.0;  // the share's splats at 1 and at ½, before the gathers; a gather
    // Under a time limit the share is probed in portions. A deadline that passes during it, or
    // leaves too little time for the halves' gathers, cuts the probe short: no later pass
    // follows, so no scale is chosen (cutShort).
    const size_t probed = landHalves(indirect, 0, share, ps, parts, slots, seconds, timeUp);
    if (probed < share || (time.lacks && time.lacks(2.0 * time.gather))) {
        covered = cutShort(indirect, probed, ps, parts, slots, sum, timeUp);
        return 1.f;
    }
    gatherHalves(parts, slots, mine, gather);
    std::vector<float> light;
    KernelScaleProbe probe;
    // Rank 0 says whether the rest is probed too (−1), or the scale chosen. Under a time limit,
    // the rest only where its halves and their gathers fit the time left.
    const double rest = (seconds[0] + seconds[1]) * double(n - share) / double(std::max<size_t>(share, 1));
    const bool late = time.lacks && time.lacks(rest + 2.0 * time.gather);
    double scale = 1.0;
    if (c_.ranks.rank() == 0) {
        probe = measure(parts, double(KernelScaleProbe::kShare), light);
        scale = !late && probeWidens(probe) ? -1.0 : choose(probe, light, seconds, gather, whole, other);
    }
    c_.ranks.broadcast(&scale, 1);
    widened_ = scale < 0.0;
    if (widened_) {
        FixedFilm rest[4];
        std::vector<int64_t> restSlots[4];
        double unusedSeconds[2], unusedGather = 0.0;
        landHalves(indirect, share, n, ps, rest, restSlots, unusedSeconds, nullptr);
        gatherHalves(rest, restSlots, mine, unusedGather);
        if (c_.ranks.rank() == 0) {
            for (int j = 0; j < 4; ++j) {
                std::vector<int64_t>& to = parts[j].buffers[kIndirect];
                const std::vector<int64_t>& from = rest[j].buffers[kIndirect];
                for (size_t i = 0; i < values_; ++i) FixedFilm::addSaturating(to[i], from[i]);
            }
            probe = measure(parts, 1, light);
            scale = choose(probe, light, seconds, gather, whole, other);
        }
        c_.ranks.broadcast(&scale, 1);
    }
    const float m = float(scale);
    for (FixedFilm& part : parts) part = FixedFilm();  // the halves are done with: freed before the rest is splatted
    keep(mine[keptProbeScale(m) < 1.f ? 1 : 0], sum);
    if (widened_) {
        covered = UINT64_MAX;  // every path's indirect photons
        return m;
    }
    covered = splatRest(indirect, share, m, ps, sum, timeUp);
    return m;
}

uint64_t KernelScaleProbeStep::splatRest(const PhotonMap& indirect, size_t from, float m, const PhotonSettings& ps, FixedFilm& sum,
                                         const std::function<bool()>& timeUp, std::vector<int64_t>* sums) {
    FixedFilm part;  // the splat's layers only
    part.width = c_.width, part.height = c_.height;
    for (int l = 0; l < kProbeLayers; ++l) part.buffers[l].assign(values_, 0);
    const uint64_t covered = targets_.splat(scaledKernels(c_.scene, slice(indirect, from, indirect.rays.size()), kPhotonIndirect, m, ps),
                                            splat_, part, &totals_.splat, &totals_.coverage, timeUp, sums);
    sum.add(part);
    return covered;
}

uint64_t KernelScaleProbeStep::cutShort(const PhotonMap& indirect, size_t probed, const PhotonSettings& ps, FixedFilm parts[4],
                                        std::vector<int64_t> slots[4], FixedFilm& sum, const std::function<bool()>& timeUp) {
    const size_t n = indirect.rays.size();
    for (size_t i = 0; i < slots[1].size(); ++i) FixedFilm::addSaturating(slots[0][i], slots[1][i]);
    std::vector<int64_t>& light = parts[0].buffers[kIndirect];
    for (size_t i = 0; i < values_; ++i) FixedFilm::addSaturating(light[i], parts[1].buffers[kIndirect][i]);
    uint64_t covered = probed < n ? indirect.rays[probed].path : UINT64_MAX;  // the paths before the first one not probed
    // Where the whole share was probed with time left, the rest follow at scale 1 until the
    // deadline, onto the same receivers' sums.
    if (probed < n && timeUp && !timeUp()) covered = splatRest(indirect, probed, 1.f, ps, sum, timeUp, &slots[0]);
    targets_.gather({&slots[0]}, {&parts[0]}, splat_);
    keep(light, sum);
    c_.stats.setCount("kernel_probe_cut", 1);
    c_.stats.setCount("kernel_probe_widened", 0);
    return covered;
}

void KernelScaleProbeStep::keep(const std::vector<int64_t>& kept, FixedFilm& sum) const {
    std::vector<int64_t>& pass = sum.buffers[kIndirect];
    for (size_t i = 0; i < values_; ++i) FixedFilm::addSaturating(pass[i], kept[i]);
}

PhotonRay KernelScaleProbeStep::asSplatted(const RenderContext& c, const PhotonMap& traced, size_t index, float m, bool widened,
                                           const PhotonSettings& ps) {
    PhotonMap part = traced;
    part.rays.clear();
    const bool indirect = traced.rays[index].cls == kPhotonIndirect;
    size_t at = 0;
    for (size_t i = 0; i < traced.rays.size(); ++i) {
        if ((traced.rays[i].cls == kPhotonIndirect) != indirect) continue;
        if (i == index) at = part.rays.size();
        part.rays.push_back(traced.rays[i]);
    }
    if (indirect) {
        const size_t share = widened ? part.rays.size() : part.rays.size() / KernelScaleProbe::kShare;
        const bool probed = at < share;
        part = scaledKernels(c.scene, probed ? slice(part, 0, share) : slice(part, share, part.rays.size()),
                             kPhotonIndirect, probed ? keptProbeScale(m) : m, ps);
        at -= probed ? 0 : share;
    }
    return part.rays[at];
}

KernelScaleProbe KernelScaleProbeStep::measure(const FixedFilm halves[4], double share, std::vector<float>& light) const {
    const int64_t *A = halves[0].buffers[kIndirect].data(), *B = halves[1].buffers[kIndirect].data(),
                  *C = halves[2].buffers[kIndirect].data(), *D = halves[3].buffers[kIndirect].data();
    light.assign(values_, 0.f);
    for (size_t i = 0; i < values_; ++i) {
        const int ch = int(i % 3);
        light[i] = eye_.film.layers[kEmission][i / 3][ch] + eye_.film.layers[kDirect][i / 3][ch] +
                   float(double(A[i] + B[i]) * share / FixedFilm::kScale);
    }
    return probeKernelScale(A, B, C, D, light, eye_.film.width, FixedFilm::kScale, share);
}

double KernelScaleProbeStep::choose(const KernelScaleProbe& probe, const std::vector<float>& light, const double seconds[2],
                                    double gather, const Timer& whole, double other) {
    KernelScalePlan plan;
    plan.passes = c_.cfg.renderPassCount();
    plan.alpha = c_.cfg.alpha;
    if (c_.cfg.timeLimit > 0.0) {  // the user asked for time: the passes are counted by it
        plan.timed = true;
        plan.secondsLeft = c_.cfg.timeLimit - whole.seconds();
        plan.passOther = other;
        plan.restShare = widened_ ? 0.0 : 1.0 - 1.0 / KernelScaleProbe::kShare;
        // a + b·h² for the share, from its two splats (b: the part that grows with the
        // kernel's area), then for all the indirect photons, and a pass's one gather.
        const double b = std::max(0.0, seconds[0] - seconds[1]) * 4.0 / 3.0, a = std::max(0.0, seconds[0] - b);
        plan.splatFixed = a * KernelScaleProbe::kShare + gather;
        plan.splatScaled = b * KernelScaleProbe::kShare;
        plan.passesPerRound = c_.ranks.size();
    }
    const float scale = chooseKernelScale(probe, plan);
    if (plan.timed) nextSeconds_ = plan.passOther + kWorthStarting * splatSeconds(plan, scale);
    if (plan.timed && !eye_.filmNoise.empty()) {
        rounds_ = roundsNoise(eye_, light, noiseAtScale(probe, scale), c_.stats);
        rounds_.roundSeconds = splatSeconds(plan, scale);
        rounds_.secondsLeft = plan.secondsLeft;
    }
    const double least = expectedKernelError(probe, plan, scale);
    c_.stats.setCount("kernel_probe_gain", least > 0.0 ? expectedKernelError(probe, plan, 1.f) / least : 1.0);
    c_.stats.setCount("kernel_probe_noise", probe.noise);
    c_.stats.setCount("kernel_probe_finer_noise", probe.finerNoise);
    c_.stats.setCount("kernel_probe_bias", probe.bias());
    c_.stats.setCount("kernel_probe_bias_significance", probe.significance());
    c_.stats.setCount("kernel_probe_widened", widened_ ? 1 : 0);
    return scale;
}

}  // namespace rs
