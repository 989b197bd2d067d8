// Cut-out surfaces (glTF alphaMode MASK and BLEND) in every ray query, against the answer
// Lambert's law gives: a card of a 4 × 4 alpha checker between the sun and a floor, seen from
// straight above, shows half card and half lit floor; a card of uniform alpha ½ blended
// stochastically shows the card half the time and lets half the sunlight through.
#include <gtest/gtest.h>

#include "core/log.h"
#include "render.h"
#include "test_scenes.h"

using namespace rs;
using namespace rs::test;

namespace {

// Floor (ρ 0.6) at y = 0 and card (ρ 0.3) at y = 1 over x, z ∈ [−1, 1], the card's uv = the
// square mapped to [0, 1]²; the sun straight down with E = π, so that radiance = ρ where lit.
// The camera 100 m up sees x, z ∈ [−0.8, 0.8] of the card: columns of 0.3, 0.5, 0.5, 0.3 m of
// the texels, so the checker's solid texels fill half the view.
Scene cardOverFloor(AlphaMode mode, bool checker) {
    Scene s;
    s.path = "card over a floor";
    const uint32_t floor = addMaterial(s, MaterialKind::Lambert, Vec3(0.6f));
    const uint32_t card = addMaterial(s, MaterialKind::Lambert, Vec3(0.3f));
    std::vector<uint8_t> rgba(4 * 16, 255);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) rgba[size_t(4 * (4 * y + x) + 3)] = checker ? uint8_t(255 * ((x + y + 1) % 2)) : 255;
    s.textures.push_back(Texture("card", 4, 4, rgba.data(), true, true));
    s.materials[card].baseColorTexture.texture = 0;
    s.materials[card].alphaMode = mode;
    s.materials[card].opacity = checker ? 1.f : 0.5f;
    addQuad(s, {-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}, floor);
    addQuad(s, {-1, 1, -1}, {-1, 1, 1}, {1, 1, 1}, {1, 1, -1}, card);
    for (size_t k = s.uvs.size() - 6; k < s.uvs.size(); ++k) {
        const Vec3 p = s.positions[k];
        s.uvs[k] = Vec2(0.5f * (p.x + 1.f), 0.5f * (p.z + 1.f));
    }
    PunctualLight sun;
    sun.type = LightType::Directional;
    sun.direction = Vec3(0, -1, 0);
    sun.intensity = Vec3(kPi);
    s.lights.push_back(sun);
    s.cameras.push_back(lookAt({0, 100, 0}, {0, 0, 0}, {0, 0, -1}, 2.f * std::atan(0.8f / 99.f)));
    s.computeBounds();
    return s;
}

RenderConfig config(Method method) {
    RenderConfig cfg;
    cfg.output = "unused.exr";
    cfg.method = method;
    cfg.width = cfg.height = 32;
    cfg.photons = 20000;
    cfg.passes = method == Method::Path ? 1 : 2;
    cfg.spp = method == Method::Path ? 64 : 0;
    return cfg;
}

}  // namespace

TEST(Cutout, MaskedCheckerShowsHalfCardHalfLitFloor) {
    const Scene s = cardOverFloor(AlphaMode::Mask, true);
    for (Method m : {Method::Splat, Method::Path}) {
        const RenderResult r = render(s, config(m), silentReporter());
        EXPECT_NEAR(layerMean(r.film, kDirect), 0.5 * 0.3 + 0.5 * 0.6, 0.01) << methodName(m);
    }
    // Opaque, the card hides the floor.
    const RenderResult opaque = render(cardOverFloor(AlphaMode::Opaque, true), config(Method::Path), silentReporter());
    EXPECT_NEAR(layerMean(opaque.film, kDirect), 0.3, 0.003);
}

TEST(Cutout, BlendedCardShowsHalfAndPassesHalfTheSun) {
    const Scene s = cardOverFloor(AlphaMode::Blend, false);
    const RenderResult splat = expectSamePixelsWhateverTheThreadCount(s, config(Method::Splat));
    const RenderResult path = render(s, config(Method::Path), silentReporter());
    for (const RenderResult* r : {&splat, &path})
        EXPECT_NEAR(layerMean(r->film, kDirect), 0.5 * 0.3 + 0.5 * 0.5 * 0.6, 0.01);
}

// The masked checker card against the same shape cut as geometry: its eight solid texels as
// quads of their own. Every 8 × 8-pixel block of the direct and indirect layers agrees (path
// tracer, the floor's and card's light through and around the holes).
TEST(Cutout, MaskedCardEqualsTheSameShapeAsGeometry) {
    const Scene masked = cardOverFloor(AlphaMode::Mask, true);
    Scene cut = cardOverFloor(AlphaMode::Opaque, true);
    // Drop the card's two triangles, add its solid texels: texel (i, j) covers x = −1 + 0.5i,
    // z = −1 + 0.5j (uv = ((x + 1)/2, (z + 1)/2)); solid where (i + j + 1) is odd.
    const uint32_t card = cut.triMaterial.back();
    for (int k = 0; k < 2; ++k) {
        cut.positions.resize(cut.positions.size() - 3);
        cut.normals.resize(cut.normals.size() - 3);
        cut.uvs.resize(cut.uvs.size() - 3);
        cut.triMaterial.pop_back();
        cut.triObject.pop_back();
    }
    cut.materials[card].baseColorTexture.texture = -1;
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
            if ((i + j + 1) % 2 == 0) continue;
            const float x0 = -1.f + 0.5f * i, z0 = -1.f + 0.5f * j;
            addQuad(cut, {x0, 1, z0}, {x0, 1, z0 + 0.5f}, {x0 + 0.5f, 1, z0 + 0.5f}, {x0 + 0.5f, 1, z0}, card);
        }
    cut.computeBounds();
    RenderConfig cfg = config(Method::Path);
    cfg.spp = 256;
    const RenderResult a = render(masked, cfg, silentReporter());
    const RenderResult b = render(cut, cfg, silentReporter());
    for (int layer : {kDirect, kIndirect}) {
        double worst = 0.0;
        for (int by = 0; by < 32; by += 8)
            for (int bx = 0; bx < 32; bx += 8) {
                double sa = 0.0, sb = 0.0;
                for (int y = by; y < by + 8; ++y)
                    for (int x = bx; x < bx + 8; ++x) {
                        const Vec3 va = a.film.layers[layer][size_t(y) * 32 + x], vb = b.film.layers[layer][size_t(y) * 32 + x];
                        sa += double(va.x) + va.y + va.z;
                        sb += double(vb.x) + vb.y + vb.z;
                    }
                worst = std::max(worst, std::abs(sa - sb) / std::max(sb, 1e-6));
            }
        EXPECT_LT(worst, layer == kDirect ? 0.01 : 0.05) << layerName(layer);
    }
}
