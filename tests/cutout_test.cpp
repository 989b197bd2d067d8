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
    Texture t;
    t.width = t.height = 4;
    t.texels.assign(16, Vec3(1.f));
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) t.alpha.push_back(checker ? float((x + y + 1) % 2) : 1.f);
    s.textures.push_back(t);
    s.materials[card].baseColorTexture = 0;
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
    Camera c;
    c.position = {0, 100, 0};
    c.forward = {0, -1, 0};
    c.up = {0, 0, -1};
    c.right = glm::cross(c.forward, c.up);
    c.yfov = 2.f * std::atan(0.8f / 99.f);
    c.aspect = 1.f;
    s.cameras.push_back(c);
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
