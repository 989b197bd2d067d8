// Textures (lib/scene/texture.h): 4 bytes a texel plus the mip chain, box-filtered levels that
// keep the image's mean, sRGB decoded as the standard's formula says, and a fine checker seen
// from afar rendering to its mean instead of to noise.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "test_scenes.h"

namespace rs {
namespace {

// The standard's formula in double (IEC 61966-2-1), apart from the library's float version.
double srgbDecoded(int code) {
    const double c = code / 255.0;
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

std::vector<uint8_t> randomRgba(int w, int h, uint32_t seed) {
    std::mt19937 rng(seed);
    std::vector<uint8_t> v(4 * size_t(w) * size_t(h));
    for (uint8_t& x : v) x = uint8_t(rng() & 255u);
    return v;
}

// The mean of a level's linear texels, per channel.
glm::dvec4 levelMean(const Texture& t, int level) {
    glm::dvec4 sum(0.0);
    for (int y = 0; y < t.levelHeight(level); ++y)
        for (int x = 0; x < t.levelWidth(level); ++x) sum += glm::dvec4(t.texel(level, x, y));
    return sum / double(t.levelWidth(level) * t.levelHeight(level));
}

TEST(Texture, HoldsFourBytesATexelPlusItsMips) {
    const int w = 64, h = 32;
    const std::vector<uint8_t> rgba = randomRgba(w, h, 1);
    const Texture t("t", w, h, rgba.data(), true, true);
    // Levels 64×32, 32×16, 16×8, 8×4, 4×2, 2×1, 1×1.
    ASSERT_EQ(t.levelCount(), 7);
    size_t texels = 0;
    for (int l = 0; l < t.levelCount(); ++l) {
        EXPECT_EQ(t.levelWidth(l), std::max(1, w >> l));
        EXPECT_EQ(t.levelHeight(l), std::max(1, h >> l));
        texels += size_t(t.levelWidth(l)) * size_t(t.levelHeight(l));
    }
    EXPECT_EQ(texels, 2731u);
    EXPECT_EQ(t.bytes(), 4 * texels);  // under 4 × 4/3 bytes a texel of the image
    EXPECT_LT(double(t.bytes()), 4.0 * 4.0 / 3.0 * w * h + 4.0);
    // 16-bit images stay 16-bit: 8 bytes a texel.
    const std::vector<uint16_t> wide(4 * size_t(w) * size_t(h), 40000);
    const Texture t16("t16", w, h, wide.data(), false, false);
    EXPECT_TRUE(t16.sixteenBit());
    EXPECT_EQ(t16.bytes(), 8 * texels);
    EXPECT_EQ(t16.texel(0, 5, 7).x, 40000.f / 65535.f);
}

// Every level's mean is level 0's, also for sizes that do not halve evenly (the box filter
// weighs the texels a span cuts by the part inside), for colour (averaged in linear values) and
// data textures, to within the 8-bit rounding of each level.
TEST(Texture, EveryMipLevelKeepsTheMean) {
    for (const auto& [w, h] : {std::pair{64, 64}, std::pair{37, 23}, std::pair{1, 50}}) {
        const std::vector<uint8_t> rgba = randomRgba(w, h, uint32_t(w * h));
        for (bool srgb : {true, false}) {
            const Texture t("t", w, h, rgba.data(), srgb, true);
            const glm::dvec4 mean0 = levelMean(t, 0);
            for (int l = 1; l < t.levelCount(); ++l) {
                const glm::dvec4 mean = levelMean(t, l);
                for (int c = 0; c < 4; ++c)
                    EXPECT_NEAR(mean[c], mean0[c], 4e-3) << w << "x" << h << " srgb " << srgb << " level " << l << " channel " << c;
            }
        }
    }
}

// A black-and-white checker of single texels: its first mip level is the grey of their linear
// mean (0.5), not of their sRGB codes' mean (0.5 in sRGB is 0.21 linear).
TEST(Texture, MipsAverageInLinearValues) {
    std::vector<uint8_t> rgba(4 * 16);
    for (int i = 0; i < 16; ++i)
        for (int c = 0; c < 4; ++c) rgba[size_t(4 * i + c)] = ((i % 4 + i / 4) % 2 || c == 3) ? 255 : 0;
    const Texture t("checker", 4, 4, rgba.data(), true, false);
    for (int l = 1; l < t.levelCount(); ++l)
        EXPECT_NEAR(t.texel(l, 0, 0).x, 0.5, 0.004) << "level " << l;
}

// Each 8-bit sRGB code decodes to the formula's linear value, as the float texels of before did;
// alpha and data textures read code / 255.
TEST(Texture, EightBitSrgbDecodesByTheFormula) {
    std::vector<uint8_t> rgba(4 * 256);
    for (int k = 0; k < 256; ++k) rgba[size_t(4 * k)] = rgba[size_t(4 * k + 1)] = rgba[size_t(4 * k + 2)] = rgba[size_t(4 * k + 3)] = uint8_t(k);
    const Texture colour("ramp", 256, 1, rgba.data(), true, true), data("ramp", 256, 1, rgba.data(), false, true);
    for (int k = 0; k < 256; ++k) {
        const Vec4 c = colour.texel(0, k, 0);
        EXPECT_NEAR(c.x, srgbDecoded(k), 1e-6 * (1.0 + srgbDecoded(k))) << k;
        EXPECT_EQ(c.y, c.x);
        EXPECT_EQ(c.w, float(k) / 255.f);                      // alpha is linear
        EXPECT_EQ(colour.alphaAt(k), float(k) / 255.f);        // what the alpha test reads
        EXPECT_EQ(data.texel(0, k, 0).x, float(k) / 255.f);    // data textures are linear
        // sample() at lod 0 on a texel's centre is that texel (bilinear weights 1, 0).
        EXPECT_EQ(colour.sample(Vec2((k + 0.5f) / 256.f, 0.5f), 0.f).x, c.x);
    }
}

// A mip texel is the 8-bit code nearest to its linear value: for every pair of codes (a, b) side
// by side, the level below holds the code whose linear value is nearest to the pair's mean,
// found here by trying all 256 (either of two codes equally near).
TEST(Texture, MipTexelsRoundToTheNearestCode) {
    for (bool srgb : {true, false}) {
        std::vector<uint8_t> rgba(4 * 256);
        for (int k = 0; k < 256; ++k) rgba[size_t(4 * k)] = uint8_t(k);
        const Texture ramp("ramp", 256, 1, rgba.data(), srgb, false);
        rgba.assign(4 * 512, 0);
        for (int a = 0; a < 256; ++a) {
            for (int b = 0; b < 256; ++b) rgba[size_t(8 * b)] = uint8_t(a), rgba[size_t(8 * b + 4)] = uint8_t(b);
            const Texture pairs("pairs", 512, 1, rgba.data(), srgb, false);
            for (int b = 0; b < 256; ++b) {
                const float mean = 0.5f * ramp.texel(0, a, 0).x + 0.5f * ramp.texel(0, b, 0).x;
                float best = 2.f;
                for (int k = 0; k < 256; ++k) best = std::min(best, std::abs(ramp.texel(0, k, 0).x - mean));
                ASSERT_LE(std::abs(pairs.texel(1, b, 0).x - mean), best + 1e-7f) << "srgb " << srgb << " codes " << a << ", " << b;
            }
        }
    }
}

// lodOf: a footprint as wide as one texel is level 0, 2^k texels is level k.
TEST(Texture, LodIsLog2OfTheTexelsAFootprintSpans) {
    const std::vector<uint8_t> rgba(4 * 256 * 256, 128);
    const Texture t("t", 256, 256, rgba.data(), true, false);
    EXPECT_FLOAT_EQ(t.lodOf(1.f / 256.f), 0.f);
    EXPECT_FLOAT_EQ(t.lodOf(16.f / 256.f), 4.f);
    EXPECT_EQ(t.lodOf(0.f), 0.f);
}

// A quad carrying a 512² checker of single texels (black and white), seen from far enough that
// a pixel spans about 16 texels: each pixel's first-hit albedo is the checker's mean, 0.5, with
// little spread between pixels, by the path tracer and by the splat method's eye pass. Read at
// level 0 (no mip-maps, a point footprint) each pixel's one sample lands on one texel or
// between two: the albedo spreads over [0, 1].
class FarChecker : public ::testing::TestWithParam<Method> {
protected:
    // The checker on the quad |x|, |y| ≤ 0.6 at z = zChecker, facing +z (or −z when `flipped`).
    static Scene checkerScene(float zChecker, bool flipped) {
        Scene s;
        s.path = "far checker";
        const uint32_t m = test::addMaterial(s, MaterialKind::Lambert, Vec3(1.f));
        const int n = 512;
        std::vector<uint8_t> rgba(4 * size_t(n) * size_t(n));
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x)
                for (int c = 0; c < 4; ++c) rgba[4 * (size_t(y) * n + size_t(x)) + size_t(c)] = ((x + y) % 2 || c == 3) ? 255 : 0;
        s.textures.push_back(Texture("checker", n, n, rgba.data(), true, false));
        s.materials[m].baseColorTexture.texture = 0;
        const float z = zChecker, e = 0.6f;
        if (flipped) test::addQuad(s, {-e, -e, z}, {-e, e, z}, {e, e, z}, {e, -e, z}, m);
        else test::addQuad(s, {-e, -e, z}, {e, -e, z}, {e, e, z}, {-e, e, z}, m);
        const Vec2 uv[6] = {{0, 0}, {1, 0}, {1, 1}, {0, 0}, {1, 1}, {0, 1}};
        for (int i = 0; i < 6; ++i) s.uvs[size_t(i)] = uv[i];
        return s;
    }
    // Renders the albedo at 32 × 32, one sample a pixel, from (0, 0, zCamera) looking down −z
    // (yfov 0.5: a pixel spans 2·tan(0.25)/32 ≈ 0.016 rad, at 2.2 m 0.036 m ≈ 15 texels), and
    // expects every pixel near the checker's mean.
    static void expectMeanGrey(Scene& s, float zCamera, Method method, bool orthographic = false) {
        s.cameras.push_back(test::lookAt({0, 0, zCamera}, {0, 0, 0}, {0, 1, 0}, 0.5f));
        if (orthographic) {
            s.cameras.back().projection = Projection::Orthographic;
            s.cameras.back().ymag = 0.55f;  // a pixel 1.1 m / 32 wide: 15 texels
        }
        s.computeBounds();
        RenderConfig cfg;
        cfg.output = "unused.exr";
        cfg.method = method;
        cfg.width = cfg.height = 32;
        cfg.spp = 1;
        cfg.directSpp = 1;
        cfg.passes = 1;
        cfg.threads = 1;
        const RenderResult r = render(s, cfg, silentReporter());
        double sum = 0.0, sumSq = 0.0;
        for (const Vec3& a : r.film.albedo) {
            sum += a.x;
            sumSq += double(a.x) * a.x;
        }
        const double count = double(r.film.albedo.size()), mean = sum / count;
        const double sd = std::sqrt(std::max(0.0, sumSq / count - mean * mean));
        EXPECT_NEAR(mean, 0.5, 0.02);
        EXPECT_LT(sd, 0.03);
    }
};

TEST_P(FarChecker, RendersToItsMean) {
    Scene s = checkerScene(0.f, false);
    expectMeanGrey(s, 2.2f, GetParam());
}

// An orthographic camera's rays are as wide as a pixel of its view and do not spread: 0.1 m
// away (where a pinhole's pixel would span 0.7 texels: level 0) a pixel still spans 15.
TEST_P(FarChecker, OrthographicViewRendersToItsMean) {
    Scene s = checkerScene(0.f, false);
    expectMeanGrey(s, 0.1f, GetParam(), true);
}

// The same checker seen in a mirror (z = 0, facing the camera at z = 1.1; the checker just
// behind the camera, facing the mirror): the cone keeps widening past the mirror, 2.25 m in all.
TEST_P(FarChecker, SeenInAMirrorRendersToItsMean) {
    Scene s = checkerScene(1.15f, true);
    const uint32_t mirror = test::addMaterial(s, MaterialKind::Mirror, Vec3(1.f));
    s.materials[mirror].metallic = 1.f;
    s.materials[mirror].roughness = 0.f;
    test::addQuad(s, {-0.6f, -0.6f, 0.f}, {0.6f, -0.6f, 0.f}, {0.6f, 0.6f, 0.f}, {-0.6f, 0.6f, 0.f}, mirror);
    expectMeanGrey(s, 1.1f, GetParam());
}

INSTANTIATE_TEST_SUITE_P(Texture, FarChecker, ::testing::Values(Method::Path, Method::Splat),
                         [](const auto& info) { return std::string(methodName(info.param)); });

}  // namespace
}  // namespace rs
