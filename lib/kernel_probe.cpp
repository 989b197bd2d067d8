#include "kernel_probe.h"

#include <algorithm>
#include <cmath>

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

// The scale at which the first pass keeps its probed share's light, for the scale m chosen.
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

float KernelScaleProbeStep::run(const PhotonMap& indirect, const PhotonSettings& ps, FixedFilm& sum, const Timer& whole,
                                double other, const std::function<bool()>& timeUp, uint64_t& covered) {
    const size_t share = indirect.rays.size() / KernelScaleProbe::kShare;
    FixedFilm parts[4];  // A, B, C, D: their indirect layer only
    std::vector<int64_t> slots[4];
    double seconds[2];  // the share's splat at 1 and at ½, before the gathers
    for (int f = 0; f < 2; ++f) {
        Timer t;
        const PhotonMap scaled = scaledKernels(c_.scene, slice(indirect, 0, share), kPhotonIndirect, f ? 0.5f : 1.f, ps);
        for (int h = 0; h < 2; ++h) {
            FixedFilm& part = parts[2 * f + h];
            part.width = c_.width, part.height = c_.height;
            part.buffers[kIndirect].assign(values_, 0);
            targets_.land(slice(scaled, h ? share / 2 : 0, h ? scaled.rays.size() : share / 2), splat_, part,
                          slots[2 * f + h], f == 0 ? &totals_.splat : nullptr, f == 0 ? &totals_.coverage : nullptr);
        }
        seconds[f] = t.seconds();
    }
    // The receivers searched once for B, C and D; A's gather alone is timed as a pass's.
    Timer gathering;
    targets_.gather({&slots[0]}, {&parts[0]}, splat_);
    const double gather = gathering.seconds();
    targets_.gather({&slots[1], &slots[2], &slots[3]}, {&parts[1], &parts[2], &parts[3]}, splat_);
    std::vector<int64_t> mine[2];  // this rank's light of the share at 1 and at ½
    for (int j = 0; j < 4; ++j) {
        std::vector<int64_t>& light = parts[j].buffers[kIndirect];
        mine[j / 2].resize(values_);
        for (size_t i = 0; i < values_; ++i) mine[j / 2][i] += light[i];
        c_.ranks.sumAtRoot(light);
    }
    double scale = c_.ranks.rank() == 0 ? choose(parts, seconds, gather, whole, other) : 1.0;
    c_.ranks.broadcast(&scale, 1);
    const float m = float(scale);
    for (int j = 0; j < 4; ++j) {  // the halves are done with: freed before the rest is splatted
        parts[j] = FixedFilm();
        slots[j] = std::vector<int64_t>();
    }
    std::vector<int64_t>& light = sum.buffers[kIndirect];
    const std::vector<int64_t>& kept = mine[keptProbeScale(m) < 1.f ? 1 : 0];
    for (size_t i = 0; i < values_; ++i) FixedFilm::addSaturating(light[i], kept[i]);
    FixedFilm part;  // the splat's layers only
    part.width = c_.width, part.height = c_.height;
    for (int l = 0; l < kProbeLayers; ++l) part.buffers[l].assign(values_, 0);
    covered = targets_.splat(scaledKernels(c_.scene, slice(indirect, share, indirect.rays.size()), kPhotonIndirect, m, ps),
                             splat_, part, &totals_.splat, &totals_.coverage, timeUp);
    sum.add(part);
    return m;
}

PhotonRay KernelScaleProbeStep::asSplatted(const RenderContext& c, const PhotonMap& traced, size_t index, float m,
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
        const size_t share = part.rays.size() / KernelScaleProbe::kShare;
        const bool probed = at < share;
        part = scaledKernels(c.scene, probed ? slice(part, 0, share) : slice(part, share, part.rays.size()),
                             kPhotonIndirect, probed ? keptProbeScale(m) : m, ps);
        at -= probed ? 0 : share;
    }
    return part.rays[at];
}

double KernelScaleProbeStep::choose(const FixedFilm halves[4], const double seconds[2], double gather, const Timer& whole,
                                    double other) {
    const int64_t *A = halves[0].buffers[kIndirect].data(), *B = halves[1].buffers[kIndirect].data(),
                  *C = halves[2].buffers[kIndirect].data(), *D = halves[3].buffers[kIndirect].data();
    std::vector<float> light(values_);
    for (size_t i = 0; i < values_; ++i) {
        const int ch = int(i % 3);
        light[i] = eye_.film.layers[kEmission][i / 3][ch] + eye_.film.layers[kDirect][i / 3][ch] +
                   float(double(A[i] + B[i]) * KernelScaleProbe::kShare / FixedFilm::kScale);
    }
    const KernelScaleProbe probe =
        probeKernelScale(A, B, C, D, light, eye_.film.width, FixedFilm::kScale);
    KernelScalePlan plan;
    plan.passes = c_.cfg.renderPassCount();
    plan.alpha = c_.cfg.alpha;
    if (c_.cfg.timeLimit > 0.0) {  // the user asked for time: the passes are counted by it
        plan.timed = true;
        plan.secondsLeft = c_.cfg.timeLimit - whole.seconds();
        plan.passOther = other;
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
    c_.stats.setCount("kernel_probe_bias_significance", probe.biasChangeSpread > 0.0 ? probe.biasChange / probe.biasChangeSpread : 0.0);
    return scale;
}

}  // namespace rs
