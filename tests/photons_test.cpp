// The photon tracer: energy bookkeeping in a closed room, quotas, determinism, radii, and the
// stratification of its quasi-random sequence; the indirect kernels' scale and its choice.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "scene/accel.h"
#include "scene/lights.h"
#include "core/log.h"
#include "core/parallel.h"
#include "splat/kernel_scale.h"
#include "splat/photons.h"
#include "core/qmc.h"
#include "test_scenes.h"

using namespace rs;
using namespace rs::test;

namespace {

// A closed 2 m room of albedo ρ, looking inwards, with a 0.5×0.5 m light just below the
// ceiling facing down; optionally a glass ball on the floor.
Scene closedRoom(float rho, bool glassBall) {
    Scene s;
    uint32_t wall = addMaterial(s, MaterialKind::Lambert, Vec3(rho));
    uint32_t light = addMaterial(s, MaterialKind::Lambert, Vec3(0.f), Vec3(10.f));
    addBox(s, {-1, 0, -1}, {1, 2, 1}, wall, /*inward=*/true);
    addQuad(s, {-0.25f, 1.9f, -0.25f}, {0.25f, 1.9f, -0.25f}, {0.25f, 1.9f, 0.25f}, {-0.25f, 1.9f, 0.25f}, light);
    if (glassBall) addSphere(s, {0.f, 0.4f, 0.f}, 0.4f, 3, addMaterial(s, MaterialKind::Glass, Vec3(1.f)));
    s.computeBounds();
    return s;
}

}  // namespace

TEST(ScrambledHalton, FirstPointsAreStratifiedPerDimension) {
    ScrambledHalton h(42, 8);
    for (auto [dim, base, count] : {std::tuple{0, 2, 1024}, std::tuple{1, 3, 729}, std::tuple{2, 5, 625}}) {
        std::vector<int> hits(count, 0);
        for (int i = 0; i < count; ++i) {
            float x = h.sample(uint64_t(i), dim);
            ASSERT_GE(x, 0.f);
            ASSERT_LT(x, 1.f);
            hits[std::min(count - 1, int(x * count))]++;
        }
        for (int c : hits) EXPECT_EQ(c, 1) << "base " << base;
    }
    ScrambledHalton other(43, 8);
    EXPECT_NE(h.sample(5, 0), other.sample(5, 0));  // the seed scrambles
}

// sample()'s shortcuts give the digit-by-digit numbers: every dimension with a shortcut and
// one past them, small indices and large ones (up to 2^64).
TEST(ScrambledHalton, ShortcutsGiveTheDigitByDigitNumbers) {
    ScrambledHalton h(7, 13);
    uint64_t x = 0x9e3779b97f4a7c15ull;
    for (int i = 0; i < 20000; ++i) {
        x = x * 6364136223846793005ull + 1442695040888963407ull;
        const uint64_t index = i < 10000 ? uint64_t(i) : x >> (x % 64);
        for (int dim = 0; dim < 13; ++dim)
            ASSERT_EQ(h.sample(index, dim), h.sampleByDigits(index, dim)) << "index " << index << ", dim " << dim;
    }
}

// Every path's first segment ends on a wall: the direct photons carry exactly the emitted
// power; the indirect ones carry Φ·ρ/(1−ρ) (every later bounce, summed) up to noise.
TEST(PhotonTracer, ClosedRoomConservesEnergy) {
    const float rho = 0.5f;
    Scene s = closedRoom(rho, false);
    RayAccel accel(s, 1);
    LightSampler lights(s);
    ThreadPool pool(2);
    PhotonSettings st;
    st.photons = 40000;
    st.maxDepth = 64;
    PhotonMap map = tracePhotons(s, accel, lights, st, pool, silentReporter());
    DVec3 sum[kPhotonClassCount] = {};
    for (const PhotonRay& r : map.rays) sum[r.cls] += DVec3(r.flux);
    double power = luminance(s.emittedPower());
    EXPECT_NEAR(sum[kPhotonDirect].x / power, 1.0, 1e-4);
    EXPECT_NEAR(sum[kPhotonIndirect].x / power, rho / (1 - rho), 0.03);
    // No glass: no caustics, and their quota went to the other classes.
    EXPECT_EQ(map.count[kPhotonCaustic], 0);
    EXPECT_EQ(map.count[kPhotonDirect] + map.count[kPhotonIndirect], st.photons);
}

// A point light outside the scene's bounds sends its photons only towards them (a half of the
// sphere for each axis it lies outside along), each with the flux of that narrower pdf: the
// direct photons on a floor carry I·Ω, Ω the floor's solid angle seen from the light, summed
// here cell by cell, for a light above the floor and for one above and beside it.
TEST(PhotonTracer, PointLightOutsideTheBoundsSendsTheFloorItsLight) {
    for (const Vec3 at : {Vec3(0.3f, 1.5f, 0.2f), Vec3(2.5f, 1.5f, 0.2f)}) {
        Scene s;
        addQuad(s, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, {-2, 0, -2}, addMaterial(s, MaterialKind::Lambert, Vec3(0.5f)));
        PunctualLight light;
        light.position = at;
        light.intensity = Vec3(3.f);
        s.lights.push_back(light);
        s.computeBounds();
        RayAccel accel(s, 1);
        LightSampler lights(s);
        ThreadPool pool(2);
        PhotonSettings st;
        st.photons = 40000;
        st.split = {1.f, 0.f, 0.f};
        const PhotonMap map = tracePhotons(s, accel, lights, st, pool, silentReporter());
        double flux = 0.0;
        for (const PhotonRay& r : map.rays) flux += r.cls == kPhotonDirect ? double(r.flux.x) : 0.0;
        const int n = 1000;
        double omega = 0.0;  // ∫ cos θ / r² dA over the floor
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                const DVec3 d = DVec3(-2.0 + 4.0 * (i + 0.5) / n, 0.0, -2.0 + 4.0 * (j + 0.5) / n) - DVec3(at);
                const double r2 = glm::dot(d, d);
                omega += (-d.y / std::sqrt(r2)) / r2 * (16.0 / (double(n) * n));
            }
        EXPECT_NEAR(flux / (3.0 * omega), 1.0, 0.01) << "light at " << at.x;
        EXPECT_EQ(map.count[kPhotonDirect], st.photons);
        // The paths the floor's photons took: each lands with the share of the allowed directions
        // the floor takes, Ω over 2π above the floor, over π above and beside it.
        const double allowed = at.x > 2.f ? kPi : 2.0 * kPi;
        EXPECT_NEAR(double(map.pathsFor[kPhotonDirect]) * omega / allowed / st.photons, 1.0, 0.02)
            << "paths sent away from the floor, light at " << at.x;
    }
}

TEST(PhotonTracer, GlassBallMakesCausticsAndQuotasHold) {
    Scene s = closedRoom(0.5f, true);
    RayAccel accel(s, 1);
    LightSampler lights(s);
    ThreadPool pool(2);
    PhotonSettings st;
    st.photons = 20000;
    PhotonMap map = tracePhotons(s, accel, lights, st, pool, silentReporter());
    EXPECT_EQ(map.count[kPhotonDirect], 4000);
    EXPECT_EQ(map.count[kPhotonIndirect], 10000);
    EXPECT_EQ(map.count[kPhotonCaustic], 6000);
    // Caustics are rarer: more paths were needed to fill them.
    EXPECT_GT(map.pathsFor[kPhotonCaustic], map.pathsFor[kPhotonDirect]);
    for (const PhotonRay& r : map.rays) {
        int c = r.cls;
        EXPECT_GE(r.radius, st.minRadius[c] * st.voxelSize * 0.9999f);
        EXPECT_LE(r.radius, st.maxRadius[c] * st.voxelSize * 1.0001f);
        EXPECT_NEAR(glm::length(r.dir), 1.f, 1e-5f);
        EXPECT_GT(r.length, 0.f);
    }
    // Caustic photons under the ball: they end on the floor beneath it.
    int under = 0;
    for (const PhotonRay& r : map.rays) {
        Vec3 end = r.origin + r.length * r.dir;
        if (r.cls == kPhotonCaustic && end.y < 1e-3f && std::hypot(end.x, end.z) < 0.5f) ++under;
    }
    EXPECT_GT(under, map.count[kPhotonCaustic] / 2);
}

TEST(PhotonTracer, ThreadCountDoesNotChangePhotons) {
    Scene s = closedRoom(0.6f, true);
    RayAccel accel(s, 2);
    LightSampler lights(s);
    PhotonSettings st;
    st.photons = 10000;
    ThreadPool one(1), two(2);
    PhotonMap a = tracePhotons(s, accel, lights, st, one, silentReporter());
    PhotonMap b = tracePhotons(s, accel, lights, st, two, silentReporter());
    ASSERT_EQ(a.rays.size(), b.rays.size());
    EXPECT_EQ(0, std::memcmp(a.rays.data(), b.rays.data(), a.rays.size() * sizeof(PhotonRay)));
}

// The probe's photons at another scale are the tracer's own at that scale, radius and reach
// (the reach to the bounds counted again in the smaller radii) to the bit.
TEST(KernelScale, ScaledKernelsAreTheTracersAtThatScale) {
    Scene s = closedRoom(0.6f, true);
    RayAccel accel(s, 2);
    LightSampler lights(s);
    ThreadPool pool(2);
    PhotonSettings st;
    st.photons = 5000;
    st.voxelSize = 0.02f;
    st.reachToBounds = true;
    const PhotonMap whole = tracePhotons(s, accel, lights, st, pool, silentReporter());
    st.classScale[kPhotonIndirect] = 0.5f;
    const PhotonMap half = tracePhotons(s, accel, lights, st, pool, silentReporter());
    const PhotonMap scaled = scaledKernels(s, whole, kPhotonIndirect, 0.5f, st);
    std::vector<PhotonRay> expected;
    for (const PhotonRay& r : half.rays)
        if (r.cls == kPhotonIndirect) expected.push_back(r);
    ASSERT_GT(expected.size(), 1000u);
    ASSERT_EQ(expected.size(), scaled.rays.size());
    EXPECT_EQ(0, std::memcmp(expected.data(), scaled.rays.data(), expected.size() * sizeof(PhotonRay)));
    EXPECT_EQ(scaled.pathsFor[kPhotonIndirect], whole.pathsFor[kPhotonIndirect]);
}

// Four halves made from a known bias and noise: the probe finds them. Pixel i has light T,
// whose kernels at scale 1 add a bias b = 0.2·T (½ of it at ½: kBiasOrder 1), and each half (an estimate
// of the pass from a half of the probe's share of its photons) noise of standard deviation σ at scale 1, 2σ at ½.
TEST(KernelScale, ProbeMeasuresBiasAndNoise) {
    const int n = 200000;
    const double sigma = 0.05, fixed = 4294967296.0, k = KernelScaleProbe::kShare;
    std::mt19937 rng(7);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> u(0.2, 2.0);
    std::vector<int64_t> a(n), b(n), c(n), d(n);
    std::vector<float> light(n);
    double bias = 0.0, noise = 0.0;
    for (int i = 0; i < n; ++i) {
        const double t = u(rng), b1 = 0.2 * t, w = 1.0 / (t * t + 0.01);
        light[i] = float(t);
        // Each half is the share's half as splatted: its estimate of the pass over kShare, halved.
        auto half = [&](double bias, double sd) { return int64_t(std::llround((t + bias + sd * g(rng)) / 2 / k * fixed)); };
        a[i] = half(b1, sigma), b[i] = half(b1, sigma);
        c[i] = half(b1 / 2, 2 * sigma), d[i] = half(b1 / 2, 2 * sigma);
        bias += w * b1 * b1;
        noise += w * 2 * (sigma / 2) * (sigma / 2) / k;  // (A + B)'s variance, for the whole pass's photons
    }
    const KernelScaleProbe p = probeKernelScale(a.data(), b.data(), c.data(), d.data(), light, 256, fixed);
    EXPECT_NEAR(p.bias() / bias, 1.0, 0.03);
    EXPECT_NEAR(p.noise / noise, 1.0, 0.02);
    EXPECT_NEAR(p.finerNoise / (4 * noise), 1.0, 0.02);
}

// The choice against the analytic optimum: one pass, E(m) = β m² + V m⁻² (bias ∝ h, noise ∝
// h⁻²), least at m = (V / β)^(1/4).
TEST(KernelScale, ChoiceIsTheLeastExpectedError) {
    KernelScalePlan one;
    one.passes = 1;
    KernelScaleProbe p;
    static_assert(kBiasOrder == 1.0);
    p.biasChange = 0.25;  // β = 1: b₁ − b_½ = b₁ / 2
    p.noise = std::pow(0.5, 4.0);
    p.finerNoise = 4.0 * p.noise;  // q = 2
    EXPECT_NEAR(chooseKernelScale(p, one), 0.5f, 0.5f * 0.036f);
    EXPECT_NEAR(expectedKernelError(p, one, 0.5f), 0.25 + 0.25, 1e-9);
    p.noise = std::pow(0.6, 4.0);  // optimum 0.6: E(1)/E(0.6) = 1.57
    p.finerNoise = 4.0 * p.noise;
    EXPECT_NEAR(chooseKernelScale(p, one), 0.6f, 0.6f * 0.036f);
    // More passes average the noise away and leave the bias: smaller kernels.
    KernelScalePlan eight = one;
    eight.passes = 8;
    EXPECT_LT(chooseKernelScale(p, eight), 0.5f);
    // Under a time limit, a cheaper splat buys more passes: smaller kernels still.
    KernelScalePlan timed = one;
    timed.timed = true;
    timed.secondsLeft = 7.0, timed.passOther = 0.2, timed.splatScaled = 0.8;
    EXPECT_LT(chooseKernelScale(p, timed), chooseKernelScale(p, eight));
}

// S's spread is that of S where nothing is blurred. Four halves of independent noise and no
// blur: S / spread scatters as a unit normal over images. A blur both halves share stands out
// of it; the same S made by a few bright photons in one half does not.
TEST(KernelScale, KeepsOnlyABlurAboveItsSpread) {
    const int width = 64, n = width * width * 3;  // blocks of 4 × 4 pixels
    const double fixed = 4294967296.0, k = KernelScaleProbe::kShare;
    auto at = [&](double v) { return int64_t(std::llround(v / 2 / k * fixed)); };  // a half of the share, as splatted
    const std::vector<float> light(n, 1.f);
    std::mt19937 rng(11);
    std::normal_distribution<double> g(0.0, 0.05);
    const int images = 400;
    double sum = 0.0, sum2 = 0.0;
    for (int image = 0; image < images; ++image) {
        std::vector<int64_t> h[4];
        for (auto& v : h)
            for (int i = 0; i < n; ++i) v.push_back(at(1.0 + g(rng)));
        const double z = probeKernelScale(h[0].data(), h[1].data(), h[2].data(), h[3].data(), light, width, fixed).significance();
        sum += z, sum2 += z * z;
    }
    const double mean = sum / images, sd = std::sqrt(sum2 / images - mean * mean);
    EXPECT_NEAR(mean, 0.0, 0.15);
    EXPECT_NEAR(sd, 1.0, 0.12);

    // No noise: in the corner block of 4 × 4 pixels, A and B brighter than C and D by δ each
    // (a blur they share), or by 4δ and δ (bright photons in A): the same S = 4 Σ w x y.
    const std::vector<int64_t> flat(n, at(1.0));
    auto corner = [&](double delta) {
        std::vector<int64_t> v = flat;
        for (int y = 0; y < 4; ++y)
            for (int i = y * width * 3; i < (y * width + 4) * 3; ++i) v[size_t(i)] = at(1.0 + delta);
        return v;
    };
    const std::vector<int64_t> shared = corner(0.02), bright = corner(0.04), faint = corner(0.01);
    const KernelScaleProbe blur = probeKernelScale(shared.data(), shared.data(), flat.data(), flat.data(), light, width, fixed);
    const KernelScaleProbe lump = probeKernelScale(bright.data(), faint.data(), flat.data(), flat.data(), light, width, fixed);
    EXPECT_NEAR(lump.biasChange / blur.biasChange, 1.0, 1e-3);
    EXPECT_GT(blur.significance(), 100.0);
    EXPECT_NEAR(lump.significance(), 16.0 / 30.0, 1e-3);  // 4·4δ² over 2·(16 − 1)δ²
    KernelScaleProbe noisy = blur, lumpy = lump;
    noisy.noise = lumpy.noise = blur.biasChange;  // a noise that makes smaller kernels pay
    noisy.finerNoise = lumpy.finerNoise = 4.0 * blur.biasChange;
    KernelScalePlan plan;
    plan.passes = 16;
    EXPECT_LT(chooseKernelScale(noisy, plan), 0.8f);
    EXPECT_EQ(chooseKernelScale(lumpy, plan), 1.f);
    // Half of the first pass's photons decide only a clear blur; the rest are probed otherwise.
    EXPECT_FALSE(probeWidens(noisy));
    EXPECT_TRUE(probeWidens(lumpy));
}

// No bias measured: the kernels stay as they are. A bias measured small and a noise that falls
// with wider kernels: wider ones, up to kMaxKernelScale. A bias whose optimum is near 1 (E(1) <
// kMinKernelGain E(m)): scale 1.
TEST(KernelScale, KeepsScaleOneWithoutAClearGain) {
    KernelScalePlan plan;
    plan.passes = 8;
    KernelScaleProbe p;
    p.noise = 1.0;
    p.finerNoise = 4.0;
    p.biasChange = -0.5;  // the bias estimate's noise
    EXPECT_EQ(chooseKernelScale(p, plan), 1.f);
    p.biasChange = 0.001;
    EXPECT_NEAR(chooseKernelScale(p, plan), kMaxKernelScale, 1e-5f);
    p.biasChange = 0.2;  // optimum a little above 1, short of a clear gain
    EXPECT_LT(expectedKernelError(p, plan, 1.f), kMinKernelGain * expectedKernelError(p, plan, 1.1f));
    EXPECT_EQ(chooseKernelScale(p, plan), 1.f);
}

// Photon rounds (kernel_scale.h): R = √(kRoundsNoiseRatio · (V/F) · (E/W)), rounded, within
// [1, kMaxAutoPhotonRounds] and what leaves two passes in the time left; 1 with nothing measured.
TEST(PhotonRounds, ChoiceBalancesTheNoiseAndTimeOfPhotonsAndFilm) {
    PhotonRoundsPlan plan;
    plan.photonNoise = 1.0, plan.filmNoise = kRoundsNoiseRatio;  // (V/F)·ratio = 1
    plan.eyeSeconds = 4.0, plan.roundSeconds = 1.0, plan.secondsLeft = 100.0;
    EXPECT_EQ(choosePhotonRounds(plan), 2);
    plan.eyeSeconds = 9.0;
    EXPECT_EQ(choosePhotonRounds(plan), 3);
    plan.photonNoise = 4.0;  // noisier photons: twice the rounds
    EXPECT_EQ(choosePhotonRounds(plan), 6);
    plan.secondsLeft = 2.0 * (9.0 + 4.0);  // two passes of 9 s and four rounds
    EXPECT_EQ(choosePhotonRounds(plan), 4);
    plan.secondsLeft = 10.0;
    EXPECT_EQ(choosePhotonRounds(plan), 1) << "not even two passes of one round";
    plan.secondsLeft = 1e6, plan.photonNoise = 1e6;
    EXPECT_EQ(choosePhotonRounds(plan), kMaxAutoPhotonRounds);
    plan.filmNoise = 0.0;
    EXPECT_EQ(choosePhotonRounds(plan), 1) << "nothing measured";
    plan.filmNoise = 1.0, plan.photonNoise = 1e-9;
    EXPECT_EQ(choosePhotonRounds(plan), 1) << "never fewer than one";
}
