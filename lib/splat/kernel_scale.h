// The indirect kernels' scale, chosen from the image (docs/design.md §7). A kernel's radius
// trades bias (light blurred over its disc, growing with h) against noise (∝
// 1/h², fewer photons under it), and which wins depends on the scene: contact shadows under a
// point light want small kernels, a room's smooth interreflection large ones. So the first
// pass measures both on half of its indirect photons (kShare; all of them where that half
// leaves it unclear, probeWidens): splatted at scale 1 in two halves A and B (its paths split
// by a hash), and with kernels half as wide in halves C and D, their flux × the
// share s (the pass's photons over the probe's). Per pixel and channel, weighted as relative MSE
// (w = 1/(μ² + 0.01)), and for the pass's photons (the probe's noise over s):
//   noise of a pass at scale 1      V = Σ w (A − B)² / s
//   noise at scale ½                V' = Σ w (C − D)² / s
//   the bias's change from 1 to ½   S = Σ w ((A + B − C − D)² − (A − C − B + D)²)
// The second square is the first's noise (the halves are independent), so S estimates
// Σ w (b₁ − b_½)², and with bias ∝ h^e (e = kBiasOrder), b₁ − b_½ = (1 − 2^−e) b₁: Σ w b₁² =
// S / (1 − 2^−e)². Over the render's P passes, whose radii shrink by r_p, a scale m then gives the
// expected error
//   E(m) = Σ w b₁² · m^2e · (mean of r_p^e)² + V · mean of (r_p m)^−q / P,
// with q from V'/V (2 for a disc), and the scale kept is the m in [¼, 1.46] of least E, where it
// promises a clear gain over 1. Under a time limit P is the whole passes that fit, averaged over
// ±15 % of a pass's time, whose splat is timed by the probe's two (a part per photon and a part
// ∝ h²).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace rs {

// How the bias grows with the kernel radius: b ∝ h^kBiasOrder. Where the irradiance bends
// smoothly a kernel's blur grows as h², but the light the probe finds blurred is at edges
// (contact shadows, the rim of a lit patch), where it grows as h. Under the point lights h²
// chose 0.52–0.66 (point_shadows, 500 px, 10 s: rel. MSE 2.2–2.5e-5) and h 0.33–0.48
// (1.8–1.9e-5; a fixed 0.35 gave 1.7e-5); direct_light within 3 %, rooms with no measured blur
// unchanged.
constexpr double kBiasOrder = 1.0;

struct KernelScaleProbe {
    // The probe's photons: one in kShare of the pass's. A quarter gave bias estimates scattered
    // by a factor of 25 over seeds on point_shadows (one seed in three found almost none and kept
    // scale 1); half of them scatter by 1.4 and cost less than the error they save.
    static constexpr int kShare = 2;
    double noise = 0.0;       // V
    double finerNoise = 0.0;  // V'
    double biasChange = 0.0;  // S
    // S's spread where nothing is blurred. S = 4 Σ w x y with x = A − C and y = B − D, the two
    // halves' changes; with no blur x and y are independent noises of mean 0, and the spread of
    // 4xy is twice that of x² − y², whose mean is 0 whatever the blur. So the spread is
    // 2 √Σ T², T the sum of w (x² − y²) over one of kBlocks × kBlocks blocks of the image (a
    // kernel's light lands on neighbouring pixels together, so blocks, not pixels, are what is
    // independent; a kernel covers as much of the image at any resolution). A blur the halves
    // share adds nothing to it; a few bright photons in one half (a glossy lobe's, a caustic's)
    // add their square.
    double biasChangeSpread = 0.0;
    static constexpr int kBlocks = 16;
    double bias() const;  // Σ w b₁²
    double significance() const { return biasChangeSpread > 0.0 ? biasChange / biasChangeSpread : biasChange > 0.0 ? 1e9 : 0.0; }
};

// From the four halves' indirect light as splatted (fixed point, pixel × rgb, rows of `width`
// pixels), the pass's light μ and the share s: the pass's indirect photons over the probe's.
KernelScaleProbe probeKernelScale(const int64_t* a, const int64_t* b, const int64_t* c, const int64_t* d,
                                  const std::vector<float>& light, int width, double fixedScale,
                                  double share = KernelScaleProbe::kShare);

struct KernelScalePlan {
    int passes = 1;            // P, with no time limit
    float alpha = 2.f / 3.f;   // the passes' shrinkage (passRadiusScale)
    // With a time limit: seconds left once the probe has measured, and one pass's seconds apart
    // from its indirect photons' splat; passes a round (ranks).
    double secondsLeft = 0.0, passOther = 0.0;
    // The indirect photons' splat at scale m takes splatFixed + splatScaled·m² seconds.
    double splatFixed = 0.0, splatScaled = 0.0;
    int passesPerRound = 1;
    bool timed = false;
    // The share of the first pass's indirect photons still to splat once the probe has chosen.
    double restShare = 1.0 - 1.0 / KernelScaleProbe::kShare;
};

constexpr float kMinKernelScale = 0.25f;
// Larger kernels too, up to 2^(11/20) = 1.46: where no blur is measured (smooth interreflection
// in closed rooms) wider kernels hold more photons.
constexpr int kLargerSteps = 11;
constexpr float kMaxKernelScale = 1.4640857f;  // 2^(11/20)
// The least E(1)/E(m) for which m is kept over 1 (measured: the probe's noise asks 1.25 on the
// glossy box, whose estimate wavers by 1.1 either way, and 1.5 on the staircase at 8 passes, one
// seed in four of which promised 1.45 from 0.62 and got 1.6 times the error; the point lights'
// gains are 1.5–5).
constexpr double kMinKernelGain = 1.5;
// And only where the measured blur stands out of its own noise: S above kBiasSignificance times
// its spread. Heavy-tailed light (a glossy lobe's or a caustic's rare bright photons) makes the
// halves differ in a few blocks, which reads as blur: the glossy box at 256 px, 16 passes,
// measures 0.1–0.4 spreads (S with no blur the halves share).
constexpr double kBiasSignificance = 2.0;
// Where half of the first pass's photons do not measure a blur kBiasSignificance spreads out,
// the rest are probed too and the scale is chosen from all of them (twice the photons: the
// spread falls by half). Under direct_light's point light at 500 px half of them measured −0.5
// to 2 spreads on five seeds of eight, all of them 2.3–5.7. It costs the rest's splat at ½:
// under a 10 s limit the interior and the daylight room (whose blur is hidden in their noise)
// come out about 1 % worse, the staircase under 20 s within noise.
inline bool probeWidens(const KernelScaleProbe& p) { return !(p.significance() > kBiasSignificance); }

// The kernel scale of pass p (0-based) from the shrinkage α: r²(n+1) = r²(n)·(n + α)/(n + 1).
float passRadiusScale(int p, float alpha);

// The m of least expected error (1 when no bias is measured, or none above its spread).
float chooseKernelScale(const KernelScaleProbe& probe, const KernelScalePlan& plan);
// A pass's seconds at scale m, by the plan's figures (with a time limit).
inline double splatSeconds(const KernelScalePlan& plan, float m) { return plan.splatFixed + plan.splatScaled * double(m) * m; }
inline double passSeconds(const KernelScalePlan& plan, float m) { return plan.passOther + splatSeconds(plan, m); }
// E(m), for the choice and its tests.
double expectedKernelError(const KernelScaleProbe& probe, const KernelScalePlan& plan, float m);
// V at scale m: the probe's noise of a pass, grown as the kernels shrink (q from V'/V).
double noiseAtScale(const KernelScaleProbe& probe, float m);

// Photon rounds (docs/design.md §9). A pass's eye pass and direct film cost E seconds and leave
// film noise F (Σ w var, weighted as V is); a round of its photons costs W seconds and leaves
// photon noise V. With R rounds a pass, P passes in time T: error (F + V/R)·P⁻¹ and
// P = T/(E + R·W), least at R = √((V/F)·(E/W)). On the staircase at 180×320 that is about 2, at
// 720×1280 about 7 (its eye pass grows with the pixels, a round's splat less).
struct PhotonRoundsPlan {
    double photonNoise = 0.0, filmNoise = 0.0;  // V (at the scale chosen), F
    double eyeSeconds = 0.0, roundSeconds = 0.0;  // E, W
    double secondsLeft = 0.0;                     // for the passes after the first
};
// The rounds: R rounded, within [1, kMaxAutoPhotonRounds] and so that two passes still fit the time
// left (the kernels shrink from pass to pass); 1 where nothing was measured.
int choosePhotonRounds(const PhotonRoundsPlan& plan);
constexpr int kMaxAutoPhotonRounds = 16;
// The first pass's V/F understates what the passes leave: F, from halves of 8 samples, stands
// 1.9 times above the variance of a film of 16 (eye_test), the direct film's samples run on as
// one sequence across the passes, so its error falls faster than F/P, and the photons' slower
// than V/P (their kernels shrink). The rounds that gave the least error at equal time, against
// √((V/F)·(E/W)) as measured: staircase 180×320 2 against 0.84, 720×1280 6 against 2.73, the
// interior at 500×500 2–4 against 0.78, point_shadows 1 against 0.45. Hence V/F × 5.
constexpr double kRoundsNoiseRatio = 5.0;

}  // namespace rs
