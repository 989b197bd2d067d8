#include "splat/kernel_scale.h"

#include <algorithm>
#include <cmath>

namespace rs {

double KernelScaleProbe::bias() const {
    const double f = 1.0 - std::pow(0.5, kBiasOrder);  // b₁ − b_½ = f·b₁
    return std::max(0.0, biasChange) / (f * f);
}

float passRadiusScale(int p, float alpha) {
    double r2 = 1.0;
    for (int n = 1; n <= p; ++n) r2 *= (n + double(alpha)) / (n + 1.0);
    return float(std::sqrt(r2));
}

KernelScaleProbe probeKernelScale(const int64_t* a, const int64_t* b, const int64_t* c, const int64_t* d,
                                  const std::vector<float>& light, int width, double fixedScale, double share) {
    KernelScaleProbe p;
    const size_t pixels = light.size() / 3, height = pixels / size_t(width);
    const int blocksX = KernelScaleProbe::kBlocks, blocksY = KernelScaleProbe::kBlocks;
    std::vector<double> blockNull(size_t(blocksX) * blocksY, 0.0);  // w (x² − y²) summed a block
    for (size_t i = 0; i < light.size(); ++i) {
        const double w = 1.0 / (double(light[i]) * light[i] + 0.01);
        const double k = share / fixedScale;  // the flux × s
        const double A = double(a[i]) * k, B = double(b[i]) * k, C = double(c[i]) * k, D = double(d[i]) * k;
        p.noise += w * (A - B) * (A - B) / share;
        p.finerNoise += w * (C - D) * (C - D) / share;
        const double x = A - C, y = B - D;  // (x + y)² − (x − y)²
        p.biasChange += w * 4.0 * x * y;
        const size_t pixel = i / 3, column = pixel % size_t(width), line = pixel / size_t(width);
        const size_t row = std::min(size_t(blocksY - 1), line * blocksY / std::max<size_t>(height, 1));
        blockNull[row * blocksX + column * blocksX / size_t(width)] += w * (x * x - y * y);
    }
    for (double t : blockNull) p.biasChangeSpread += t * t;
    p.biasChangeSpread = 2.0 * std::sqrt(p.biasChangeSpread);
    return p;
}

namespace {

// q: how the noise grows as the kernels shrink, from the two scales measured; 2 for a disc
// whose photons spread evenly, kept within [1, 3].
double noiseExponent(const KernelScaleProbe& p) {
    if (!(p.noise > 0.0) || !(p.finerNoise > 0.0)) return 2.0;
    return std::clamp(std::log2(p.finerNoise / p.noise), 1.0, 3.0);
}

}  // namespace

double noiseAtScale(const KernelScaleProbe& probe, float m) { return probe.noise * std::pow(double(m), -noiseExponent(probe)); }

int choosePhotonRounds(const PhotonRoundsPlan& plan) {
    if (!(plan.photonNoise > 0.0) || !(plan.filmNoise > 0.0) || !(plan.eyeSeconds > 0.0) || !(plan.roundSeconds > 0.0))
        return 1;
    const double best = std::sqrt(kRoundsNoiseRatio * plan.photonNoise / plan.filmNoise * plan.eyeSeconds / plan.roundSeconds);
    const double fit = std::floor((plan.secondsLeft / 2.0 - plan.eyeSeconds) / plan.roundSeconds);
    return int(std::clamp(std::min(std::round(best), fit), 1.0, double(kMaxAutoPhotonRounds)));
}

double expectedKernelError(const KernelScaleProbe& probe, const KernelScalePlan& plan, float m) {
    double passes = plan.passes;
    if (plan.timed) {
        // The first pass still splats the rest of its indirect photons at m. Only whole
        // passes are begun; the pass time is known to some ±15 %, so the passes that fit are
        // averaged over that, lest the choice turn on whether one more just fits.
        const double left = std::max(0.0, plan.secondsLeft - plan.restShare * splatSeconds(plan, m)), pass = passSeconds(plan, m);
        double fit = 0.0;
        for (double f : {0.85, 1.0, 1.15}) fit += pass > 0.0 ? std::floor(left / (pass * f)) / 3.0 : 0.0;
        passes = 1.0 + plan.passesPerRound * fit;
    }
    passes = std::clamp(passes, 1.0, 1e6);
    const int whole = std::max(1, int(std::lround(passes)));
    const double q = noiseExponent(probe), relative = double(m);
    const double e = kBiasOrder;
    double re = 0.0, noise = 0.0, pass2 = 1.0;  // pass p's r², as passRadiusScale makes it; re: mean r^e
    for (int p = 0; p < whole; ++p) {
        if (p > 0) pass2 *= (p + double(plan.alpha)) / (p + 1.0);
        re += std::pow(pass2, e / 2.0);
        noise += std::pow(pass2 * relative * relative, -q / 2.0);
    }
    re /= whole;
    noise /= whole;
    return probe.bias() * std::pow(relative, 2.0 * e) * re * re + probe.noise * noise / passes;
}

float chooseKernelScale(const KernelScaleProbe& probe, const KernelScalePlan& plan) {
    if (!(probe.significance() > kBiasSignificance)) return 1.f;  // none, or none above its spread
    // 2^(−k/20), k = −kLargerSteps … 40: ¼ to kMaxKernelScale in steps of 3.5 %. Larger kernels
    // only where a blur was measured and extrapolates small: where none shows in the share's
    // noise (direct_light, one seed in two) it may still be there, and 1.46 gave 1.34 times the
    // error.
    float best = 1.f;
    const double atOne = expectedKernelError(probe, plan, 1.f);
    double least = atOne;
    for (int k = -kLargerSteps; k <= 40; ++k) {
        const float m = float(std::exp2(-k / 20.0));
        const double e = expectedKernelError(probe, plan, m);
        if (e < least) least = e, best = m;
    }
    // The estimates come from half of a pass's photons, and heavy-tailed light (glossy
    // lobes, caustics) makes them noisy: a scale is kept only for a clear gain.
    return atOne >= kMinKernelGain * least ? best : 1.f;
}

}  // namespace rs
