// material_test: the glTF metallic-roughness model's textures against independent answers —
// the analytic radiance of normal-mapped patches under a directional light (with given and
// with computed tangents, seen from behind the mapped normal, and shadowed at a grazing light as
// Chiang et al. 2019), the GGX lobe's normal bent to reflect the viewer above the surface, photons'
// adjoint bounce under a shading normal, the dielectric
// mix against its definition and the white furnace, and equivalences: COLOR_0 × white against the same colour as a
// factor, a metallic factor of 1 × a texture saying metal 0 against metal 0, a texture
// transform of scale 2 against doubled uvs (and TEXCOORD_1 against TEXCOORD_0), a checker
// emissive texture against the untextured emitter of half its strength.
#include <gtest/gtest.h>

#include <cmath>

#include "core/sampling.h"
#include "path/path.h"
#include "render.h"
#include "scene/accel.h"
#include "scene/bsdf.h"
#include "scene/lights.h"
#include "test_scenes.h"

using namespace rs;
using namespace rs::test;

namespace {

// The uvs of the last quad added: u along `du` from corner a, v along `dv`, per metre.
void planarUvs(Scene& s, Vec3 origin, Vec3 du, Vec3 dv) {
    for (size_t c = s.positions.size() - 6; c < s.positions.size(); ++c)
        s.uvs[c] = Vec2(glm::dot(s.positions[c] - origin, du), glm::dot(s.positions[c] - origin, dv));
}

// A n × n checker of linear values a and b.
std::vector<Vec4> checker(int n, Vec3 a, Vec3 b) {
    std::vector<Vec4> t;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) t.push_back(Vec4((x + y) % 2 ? b : a, 1.f));
    return t;
}

// A small path-traced image of `s` from its first camera.
RenderResult pathImage(const Scene& s, int spp, int width = 24) {
    RenderConfig cfg;
    cfg.output = "unused.exr";
    cfg.method = Method::Path;
    cfg.width = width;
    cfg.height = width;
    cfg.spp = spp;
    cfg.passes = 1;
    cfg.threads = 2;
    return render(s, cfg, silentReporter());
}

// Every pixel of every layer within `rel` of the other image's (relative to the layer's mean).
void expectSameImage(const RenderResult& a, const RenderResult& b, float rel) {
    ASSERT_EQ(a.film.pixelCount(), b.film.pixelCount());
    for (int l = 0; l < kLayerCount; ++l) {
        const double scale = std::max(layerMean(b.film, l), 1e-6);
        for (size_t p = 0; p < a.film.pixelCount(); ++p)
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(a.film.layers[l][p][c], b.film.layers[l][p][c], rel * scale)
                    << layerName(l) << " pixel " << p << " channel " << c;
    }
}

// A 4 m floor (y = 0) under a point light, the camera looking down at it.
Scene litFloor(Vec3 baseColor, MaterialKind kind = MaterialKind::Lambert) {
    Scene s;
    const uint32_t m = addMaterial(s, kind, baseColor);
    addQuad(s, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, m);
    planarUvs(s, Vec3(-2, 0, -2), Vec3(0.25f, 0, 0), Vec3(0, 0, 0.25f));
    PunctualLight l;
    l.position = {0.5f, 1.5f, 0.3f};
    l.intensity = Vec3(6.f);
    s.lights.push_back(l);
    s.cameras.push_back(lookAt({0.3f, 2.5f, 1.8f}, {0, 0, 0}, {0, 1, 0}, 0.9f));
    s.computeBounds();
    return s;
}

}  // namespace

// -- Normal maps --------------------------------------------------------------------------

// Two 1 m patches in y = 0 (normal +Y) with u along +X and v along +Z: the tangent is +X and
// the bitangent, the image's +Y (−v), is −Z. Each reads a constant normal map: tilted 30°
// towards +T, and towards −B. Under a directional light of irradiance E (normal incidence)
// from l, each patch's radiance is albedo/π · E · (n·l) with n the tilted normal in world
// space; one path is exact (the light is a delta, nothing else is in the scene).
class NormalMap : public ::testing::TestWithParam<bool> {};

// A sun of 3 W/m² shining along −l onto `s` (its bounds set here), as the patch tests light.
void addSun(Scene& s, const Vec3& l) {
    PunctualLight sun;
    sun.type = LightType::Directional;
    sun.direction = -l;
    sun.intensity = Vec3(3.f);
    s.lights.push_back(sun);
    s.computeBounds();
}

// The radiance the path tracer sees at (x, 0, 0.5) from target + toEye, by default just above it
// (sampler stream `stream`).
float radianceAt(const Scene& s, float x, uint64_t stream = 0, Vec3 toEye = Vec3(0.2f, 1.f, 0.1f)) {
    RayAccel accel(s, 1);
    LightSampler lights(s);
    const Vec3 target(x, 0.f, 0.5f), eye = target + toEye;
    Sampler sampler(1, Stage::Test, stream);
    return tracePath(s, accel, lights, eye, glm::normalize(target - eye), 4, sampler).total().x;
}

// The grazing light of the bump-shadowing tests.
const Vec3 kGrazing = glm::normalize(Vec3(0.95f, 0.2f, 0.f));

// A 1 m Lambert patch in y = 0 whose normal map leans its normal towards +T = +X: (s, 0, c) in
// tangent space, (s, c, 0) in the world; tangents computed.
Scene tiltedPatch(float albedo, float s, float c) {
    Scene scene;
    const uint32_t m = addMaterial(scene, MaterialKind::Lambert, Vec3(albedo));
    scene.materials[m].normalTexture.texture = addTexture(scene, 1, 1, {Vec4(0.5f * Vec3(s, 0.f, c) + 0.5f, 1.f)});
    addQuad(scene, {0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}, m);
    planarUvs(scene, Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 1));
    scene.tangents.assign(scene.positions.size(), Vec4(0.f));
    computeMissingTangents(scene);
    return scene;
}

TEST_P(NormalMap, TiltedNormalsGiveTheAnalyticRadiance) {
    const bool givenTangents = GetParam();
    const float albedo = 0.7f, s30 = 0.5f, c30 = std::sqrt(3.f) / 2.f;
    const Vec3 tangentSpace[2] = {{s30, 0.f, c30}, {0.f, -s30, c30}};
    const Vec3 world[2] = {{s30, c30, 0.f}, {0.f, c30, s30}};  // x·T + y·B + z·N, T = +X, B = −Z
    Scene s;
    for (int p = 0; p < 2; ++p) {
        const uint32_t m = addMaterial(s, MaterialKind::Lambert, Vec3(albedo));
        s.materials[m].normalTexture.texture = addTexture(s, 1, 1, {Vec4(0.5f * tangentSpace[p] + 0.5f, 1.f)});
        const float x0 = 2.f * float(p);
        addQuad(s, {x0, 0, 0}, {x0, 0, 1}, {x0 + 1, 0, 1}, {x0 + 1, 0, 0}, m);
        planarUvs(s, Vec3(x0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 1));
    }
    s.tangents.assign(s.positions.size(), givenTangents ? Vec4(1, 0, 0, 1) : Vec4(0.f));
    computeMissingTangents(s);
    for (const Vec4& t : s.tangents) EXPECT_LT(glm::length(t - Vec4(1, 0, 0, 1)), 1e-5f);
    const Vec3 l = glm::normalize(Vec3(0.6f, 1.f, -0.5f));
    addSun(s, l);
    for (int p = 0; p < 2; ++p) {
        const float L = radianceAt(s, 2.f * float(p) + 0.5f, uint64_t(p));
        const float expected = albedo / kPi * 3.f * glm::dot(world[p], l);
        const float flat = albedo / kPi * 3.f * l.y;
        EXPECT_NEAR(L, expected, 0.02f * expected) << "patch " << p << " (flat would be " << flat << ")";
        EXPECT_GT(std::abs(expected - flat), 0.05f * flat);  // the test tells a tilted normal from none
    }
}

INSTANTIATE_TEST_SUITE_P(GivenAndComputedTangents, NormalMap, ::testing::Values(true, false),
                         [](const ::testing::TestParamInfo<bool>& i) { return i.param ? "Given" : "Computed"; });

// A normal map tilted towards a grazing light: the diffuse lobe takes the shadowing of
// Chiang, Li & Burley 2019 ("Taming the Shadow Terminator"), g = (ng·l) / ((ns·l)(ng·ns)),
// smoothed to −g³ + g² + g, as Blender's Cycles does; plain n·l would reflect 2.3 times as much
// as here, more than the flat patch receives.
TEST(NormalMap, GrazingLightIsShadowedAsChiang2019) {
    const float albedo = 0.7f, s30 = 0.5f, c30 = std::sqrt(3.f) / 2.f;
    Scene s = tiltedPatch(albedo, s30, c30);
    const Vec3 l = kGrazing, ns(s30, c30, 0.f), ng(0.f, 1.f, 0.f);
    addSun(s, kGrazing);
    const float L = radianceAt(s, 0.5f);
    const float g = glm::dot(ng, l) / (glm::dot(ns, l) * glm::dot(ng, ns));
    ASSERT_GT(g, 0.f);
    ASSERT_LT(g, 1.f);
    const float plain = albedo / kPi * 3.f * glm::dot(ns, l);
    const float expected = plain * (-g * g * g + g * g + g);
    EXPECT_NEAR(L, expected, 0.02f * expected) << "plain n·l: " << plain;
}

// The same light on the same patch whose shading normal leans by 30° through its vertex normals,
// with no normal map: no bump shadowing (as Cycles and Mitsuba shade smooth meshes), the plain
// albedo/π · E · (ns·l).
TEST(NormalMap, InterpolatedNormalsAloneAreNotShadowed) {
    const float albedo = 0.7f, s30 = 0.5f, c30 = std::sqrt(3.f) / 2.f;
    Scene s;
    const uint32_t m = addMaterial(s, MaterialKind::Lambert, Vec3(albedo));
    addQuad(s, {0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}, m);
    const Vec3 ns(s30, c30, 0.f);
    std::fill(s.normals.begin(), s.normals.end(), ns);
    addSun(s, kGrazing);
    const float L = radianceAt(s, 0.5f);
    const float plain = albedo / kPi * 3.f * glm::dot(ns, kGrazing);
    EXPECT_NEAR(L, plain, 1e-3f * plain);
}

// A mapped normal that faces away from the viewer still shades the diffuse lobe, which does not
// depend on the viewer (as Cycles reads it): a patch whose normal map leans 60° away from a
// grazing eye reflects albedo/π · E · (ns·l) × the bump shadowing, not the flat ng·l.
TEST(NormalMap, ANormalFacingAwayFromTheViewerStillShadesTheDiffuse) {
    const float albedo = 0.7f, s60 = std::sqrt(3.f) / 2.f, c60 = 0.5f;
    Scene s = tiltedPatch(albedo, s60, c60);
    const Vec3 l = glm::normalize(Vec3(0.8f, 1.f, 0.f)), ns(s60, c60, 0.f), ng(0.f, 1.f, 0.f);
    addSun(s, l);
    const Vec3 toEye(-1.f, 0.3f, 0.f);
    ASSERT_LT(glm::dot(ns, toEye), 0.f);
    const float L = radianceAt(s, 0.5f, 0, toEye);
    const float expected = albedo / kPi * 3.f * glm::dot(ns, l) * bumpShadowing(ng, ns, l);
    const float flat = albedo / kPi * 3.f * l.y;
    EXPECT_NEAR(L, expected, 0.02f * expected) << "flat: " << flat;
    EXPECT_GT(std::abs(expected - flat), 0.1f * flat);
}

// The GGX lobe of a mapped normal that would reflect the viewer into the surface takes the
// normal, in the plane of ng and ns, that reflects it to just above the surface
// (min(0.9·(wo·ng), 0.01) high); elsewhere the mapped normal itself.
TEST(NormalMap, TheSpecularNormalReflectsTheViewerJustAboveTheSurface) {
    const Vec3 ng(0.f, 0.f, 1.f);
    int bent = 0;
    for (float tilt : {0.2f, 0.6f, 1.0f, 1.3f})
        for (float azimuth : {0.f, 1.f, 2.5f, 3.14159f, 4.f})
            for (float elevation : {0.05f, 0.3f, 0.8f, 1.5f})
                for (float viewAzimuth : {0.f, 1.5f, 3.f}) {
                    const Vec3 ns(std::sin(tilt) * std::cos(azimuth), std::sin(tilt) * std::sin(azimuth), std::cos(tilt));
                    const Vec3 wo(std::cos(elevation) * std::cos(viewAzimuth), std::cos(elevation) * std::sin(viewAzimuth),
                                  std::sin(elevation));
                    const float height = std::min(0.9f * wo.z, 0.01f);
                    const Vec3 n = validSpecularNormal(ng, ns, wo);
                    const float reflected = (2.f * glm::dot(wo, n) * n - wo).z;
                    EXPECT_NEAR(glm::length(n), 1.f, 1e-5f);
                    EXPECT_NEAR(glm::dot(n, glm::cross(ng, ns)), 0.f, 1e-5f) << "not in the plane of ng and ns";
                    if ((2.f * glm::dot(wo, ns) * ns - wo).z >= height) {
                        EXPECT_EQ(n, ns);
                    } else {
                        ++bent;
                        EXPECT_NEAR(reflected, height, 2e-4f) << tilt << " " << azimuth << " " << elevation << " " << viewAzimuth;
                        EXPECT_GT(glm::dot(n, wo), 0.f);
                    }
                }
    EXPECT_GT(bent, 40);
}

// A photon bouncing off a normal-mapped surface carries flux per geometric area: the mean of
// Bsdf::sample's Importance weights for light arriving from l is (|ns·l| / |ng·l|) × ∫ f(ωo, l)
// |ng·ωo| dωo, the flux the camera's radiance f · |ns·l| leaves with (by quadrature over the
// hemisphere). The radiance form f · |ns·ωo| / pdf misses it by 20–45 % here. With the normal
// from a normal map, light leaves also towards directions below ns (its diffuse lobe does not
// depend on the viewer, its GGX lobe bends its normal to each viewer): the photon reaches them.
TEST(NormalMap, PhotonsBounceWithTheAdjointBsdf) {
    for (const bool mapped : {false, true}) {
        Scene s;
        const uint32_t m = addMaterial(s, MaterialKind::Mix, Vec3(0.7f, 0.6f, 0.5f));
        s.materials[m].metallic = 0.f;
        s.materials[m].roughness = 0.6f;
        if (mapped) s.materials[m].normalTexture.texture = addTexture(s, 1, 1, {Vec4(0.5f, 0.5f, 1.f, 1.f)});
        SurfacePoint sp;
        sp.ng = Vec3(0, 0, 1);
        sp.ns = glm::normalize(Vec3(0.5f, 0.f, 0.866f));
        sp.material = m;
        for (Vec3 l : {Vec3(0.7f, 0.1f, 0.5f), Vec3(-0.2f, 0.5f, 0.8f), Vec3(0.9f, -0.3f, 0.25f)}) {
            l = glm::normalize(l);
            Bsdf bsdf(s, sp, l);
            const int n = 512;
            double sampled = 0.0, quadrature = 0.0;
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j) {
                    const Vec2 u((float(i) + 0.5f) / float(n), (float(j) + 0.5f) / float(n));
                    const float uLobe = (float((i * 7 + j * 13) % n) + 0.5f) / float(n);
                    const BsdfSample b = bsdf.sample(l, uLobe, u, Transport::Importance);
                    if (b.pdf > 0.f) sampled += double(b.weight.x);
                    const float c = u.x, phi = 2.f * kPi * u.y, r = std::sqrt(1.f - c * c);
                    const Vec3 wo(r * std::cos(phi), r * std::sin(phi), c);
                    quadrature += double(bsdf.eval(wo, l).x) * c;
                }
            sampled /= double(n) * double(n);
            quadrature *= 2.0 * kPi / (double(n) * double(n)) * std::abs(glm::dot(sp.ns, l)) / std::abs(glm::dot(sp.ng, l));
            EXPECT_NEAR(sampled, quadrature, 0.01 * quadrature) << "mapped " << mapped << " l " << l.x << " " << l.y << " " << l.z;
        }
    }
}

// The Lambert + GGX mix of a dielectric layers its diffuse under the specular by albedo scaling,
// as Blender's Principled BSDF does: f = (1 − E(wo))·ρ/π + F·D·V, F = f0 + (1 − f0)(1 − v·h)^5
// of f0 0.04, GGX's D and Smith's height-uncorrelated G (design.md §3) written out here, and E the
// specular part's directional albedo, integrated here by brute force over a 2048² grid of wi.
// glTF's fresnel_mix, (1 − F)·ρ/π + F·D·V, differs: 1 − F averages above 1 − E at grazing angles.
TEST(MetallicRoughness, DielectricMixLayersTheDiffuseByTheSpecularAlbedo) {
    Scene s;
    const Vec3 rho(0.8f, 0.5f, 0.3f);
    const uint32_t m = addMaterial(s, MaterialKind::Mix, rho);
    s.materials[m].metallic = 0.f;
    for (float roughness : {0.2f, 0.5f, 0.9f}) {
        s.materials[m].roughness = roughness;
        const float a2 = roughness * roughness * roughness * roughness;
        const auto lambda = [&](float c) { return 0.5f * (std::sqrt(1.f + a2 * (1.f - c * c) / (c * c)) - 1.f); };
        const auto specular = [&](const Vec3& wo, const Vec3& wi) {
            const Vec3 h = glm::normalize(wo + wi);
            const float vh = glm::dot(wo, h), F = 0.04f + 0.96f * std::pow(1.f - vh, 5.f);
            const float d = h.z * h.z * (a2 - 1.f) + 1.f, D = a2 / (kPi * d * d);
            return F * D / (1.f + lambda(wo.z) + lambda(wi.z)) / (4.f * wo.z * wi.z);
        };
        for (float cosO : {1.f, 0.5f, 0.15f}) {
            const Vec3 wo(std::sqrt(1.f - cosO * cosO), 0.f, cosO);
            double E = 0.0;  // ∫ specular · cos θi dωi, midpoints in (cos² θi, φ): dωi cos θi = d(cos²)/2 dφ
            const int n = 2048;
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j) {
                    const float c = std::sqrt((i + 0.5f) / n), phi = 2.f * kPi * (j + 0.5f) / n, r = std::sqrt(1.f - c * c);
                    E += specular(wo, Vec3(r * std::cos(phi), r * std::sin(phi), c));
                }
            E *= kPi / (double(n) * n);
            SurfacePoint sp;
            sp.ng = sp.ns = Vec3(0, 0, 1);
            sp.material = m;
            Bsdf bsdf(s, sp, wo);
            for (Vec3 wi : {Vec3(-0.6f, 0.2f, 0.77f), Vec3(0.1f, -0.9f, 0.42f), Vec3(-0.95f, 0.f, 0.3f)}) {
                wi = glm::normalize(wi);
                const Vec3 want = float(1.0 - E) * rho / kPi + Vec3(specular(wo, wi));
                const Vec3 got = bsdf.eval(wo, wi);
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(got[c], want[c], 5e-3f * want[c]) << "roughness " << roughness << ", cos θo " << cosO;
            }
        }
    }
}

// A white dielectric mix reflects all it receives from any direction (the furnace: its albedo,
// by sampling the BSDF, is 1), at every roughness and angle: nothing is lost between the layers
// or counted twice. glTF's fresnel_mix reflects 1.15 of it at roughness 0.15 and cos θo 0.3, 1.5
// at cos θo 0.1, and 0.97 at roughness 1.
TEST(MetallicRoughness, WhiteDielectricMixReflectsAllItReceives) {
    Scene s;
    const uint32_t m = addMaterial(s, MaterialKind::Mix, Vec3(1.f));
    s.materials[m].metallic = 0.f;
    for (float roughness : {0.15f, 0.3f, 0.6f, 1.f})
        for (float cosO : {1.f, 0.6f, 0.3f, 0.1f}) {
            s.materials[m].roughness = roughness;
            SurfacePoint sp;
            sp.ng = sp.ns = Vec3(0, 0, 1);
            sp.material = m;
            const Vec3 wo(std::sqrt(1.f - cosO * cosO), 0.f, cosO);
            Bsdf bsdf(s, sp, wo);
            double albedo = 0.0;
            const int n = 256;
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j) {
                    const BsdfSample b = bsdf.sample(wo, toUnitFloat(reverseBits(uint32_t(i * n + j))), Vec2((i + 0.5f) / n, (j + 0.5f) / n),
                                                     Transport::Radiance);
                    if (b.pdf > 0.f) albedo += b.weight.x;
                }
            albedo /= double(n) * n;
            EXPECT_NEAR(albedo, 1.0, 0.01) << "roughness " << roughness << ", cos θo " << cosO;
        }
}

// -- Vertex colours, metallic-roughness, texture transforms --------------------------------

// COLOR_0 multiplies the base colour: white × a vertex colour renders as that colour given
// as the factor.
TEST(Color0, TimesWhiteEqualsTheColourAsAFactor) {
    const Vec3 colour(0.2f, 0.5f, 0.8f);
    Scene painted = litFloor(Vec3(1.f));
    painted.colors.assign(painted.positions.size(), Vec4(colour, 1.f));
    const Scene factor = litFloor(colour);
    const RenderResult a = pathImage(painted, 4), b = pathImage(factor, 4);
    EXPECT_GT(layerMean(b.film, kDirect), 0.0);
    expectSameImage(a, b, 1e-4f);
}

// A metallic factor of 1 times a metallicRoughnessTexture whose B (metal) is 0 and G 0.4 is
// the dielectric of roughness 0.4: the same image as the factors metallic 0, roughness 0.4.
TEST(MetallicRoughness, MetalFactorOneTimesTextureZeroEqualsMetalZero) {
    Scene textured = litFloor(Vec3(0.6f, 0.4f, 0.2f), MaterialKind::Mix);
    textured.materials[0].metallic = 1.f;
    textured.materials[0].roughness = 1.f;
    textured.materials[0].metallicRoughnessTexture.texture = addTexture(textured, 1, 1, {Vec4(0.f, 0.4f, 0.f, 1.f)});
    Scene plain = litFloor(Vec3(0.6f, 0.4f, 0.2f), MaterialKind::Mix);
    plain.materials[0].metallic = 0.f;
    plain.materials[0].roughness = 0.4f;
    Scene metal = plain;
    metal.materials[0].metallic = 1.f;
    const RenderResult a = pathImage(textured, 4), b = pathImage(plain, 4), c = pathImage(metal, 4);
    expectSameImage(a, b, 1e-4f);
    // And the texture matters: as metal the floor is another colour.
    EXPECT_GT(std::abs(layerMean(c.film, kDirect) - layerMean(b.film, kDirect)), 0.05 * layerMean(b.film, kDirect));
}

// KHR_texture_transform: the extension's own example, the lower-left quadrant of the image
// turned 90° (offset (0, 1), rotation π/2, scale 0.5), takes the unit square of uvs onto
// u in [0, 0.5], v in [0.5, 1].
TEST(TextureTransform, ExtensionExampleTakesTheLowerLeftQuadrant) {
    TextureTransform t;
    t.offset = {0.f, 1.f};
    t.rotation = kPi / 2.f;
    t.scale = {0.5f, 0.5f};
    const Vec2 corners[4][2] = {{{0, 0}, {0, 1}}, {{1, 0}, {0, 0.5f}}, {{0, 1}, {0.5f, 1}}, {{1, 1}, {0.5f, 0.5f}}};
    for (const auto& [uv, want] : corners) {
        const Vec2 got = t.apply(uv);
        EXPECT_NEAR(got.x, want.x, 1e-6f) << uv.x << "," << uv.y;
        EXPECT_NEAR(got.y, want.y, 1e-6f) << uv.x << "," << uv.y;
    }
}

// litFloor in white with an n × n base colour texture read through uv set `texCoord` and a
// transform of `scale`, its uvs times `uvScale` (on TEXCOORD_1, TEXCOORD_0 all zero).
Scene texturedFloor(int n, const std::vector<Vec4>& texels, int texCoord, float scale, float uvScale) {
    Scene s = litFloor(Vec3(1.f));
    Material& m = s.materials[0];
    m.baseColorTexture.texture = addTexture(s, n, n, texels);
    m.baseColorTexture.texCoord = texCoord;
    m.baseColorTexture.transform.scale = Vec2(scale);
    for (Vec2& uv : s.uvs) uv *= uvScale;
    if (texCoord == 1) s.uvs1 = s.uvs, s.uvs.assign(s.uvs.size(), Vec2(0.f));
    return s;
}

// A checker base colour read through a transform of scale 2 renders as the same texture read
// at doubled uvs; and through TEXCOORD_1 holding those doubled uvs.
TEST(TextureTransform, ScaleTwoEqualsDoubledUvs) {
    const std::vector<Vec4> texels = checker(4, Vec3(0.9f, 0.2f, 0.2f), Vec3(0.1f, 0.3f, 0.9f));
    auto checkered = [&](int texCoord, float scale, float uvScale) { return texturedFloor(4, texels, texCoord, scale, uvScale); };
    const RenderResult transformed = pathImage(checkered(0, 2.f, 1.f), 4), doubled = pathImage(checkered(0, 1.f, 2.f), 4);
    const RenderResult second = pathImage(checkered(1, 1.f, 2.f), 4), plain = pathImage(checkered(0, 1.f, 1.f), 4);
    expectSameImage(transformed, doubled, 1e-4f);
    expectSameImage(second, doubled, 1e-4f);
    double differ = 0.0;  // and the scale matters
    for (size_t p = 0; p < plain.film.pixelCount(); ++p)
        differ += glm::length(plain.film.layers[kDirect][p] - doubled.film.layers[kDirect][p]);
    EXPECT_GT(differ / double(plain.film.pixelCount()), 0.05 * layerMean(plain.film, kDirect));
}

// The mip level follows the slot's own uvs: a 256² checker of 8-texel cells, seen at about 10
// texels a pixel, through a transform of scale 2, at doubled uvs and through TEXCOORD_1 holding
// those uvs (TEXCOORD_0 all zero), filters alike: the footprint is measured in each slot's uv
// set and scaled by its transform.
TEST(TextureTransform, MipLevelFollowsTheSlotsUvsAndScale) {
    std::vector<Vec4> cells;
    for (int y = 0; y < 256; ++y)
        for (int x = 0; x < 256; ++x) cells.push_back(Vec4((x / 8 + y / 8) % 2 ? Vec3(0.1f, 0.3f, 0.9f) : Vec3(0.9f, 0.2f, 0.2f), 1.f));
    auto checkered = [&](int texCoord, float scale, float uvScale) { return texturedFloor(256, cells, texCoord, scale, uvScale); };
    const RenderResult transformed = pathImage(checkered(0, 2.f, 1.f), 4), doubled = pathImage(checkered(0, 1.f, 2.f), 4);
    const RenderResult second = pathImage(checkered(1, 1.f, 2.f), 4);
    expectSameImage(transformed, doubled, 1e-4f);
    expectSameImage(second, doubled, 1e-4f);
}

// -- Emissive textures are lights ------------------------------------------------------------

namespace {

// A 1 m emitter at y = 1 facing down over a 4 m grey floor, the camera below it seeing both:
// strength E with a black-and-white checker, or E/2 untextured.
Scene screenOverFloor(bool checkered) {
    Scene s;
    const uint32_t floor = addMaterial(s, MaterialKind::Lambert, Vec3(0.5f));
    addQuad(s, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, floor);
    const uint32_t screen = addMaterial(s, MaterialKind::Lambert, Vec3(0.f), Vec3(checkered ? 8.f : 4.f));
    addQuad(s, {-0.5f, 1, -0.5f}, {0.5f, 1, -0.5f}, {0.5f, 1, 0.5f}, {-0.5f, 1, 0.5f}, screen);
    planarUvs(s, Vec3(-0.5f, 1, -0.5f), Vec3(1, 0, 0), Vec3(0, 0, 1));
    if (checkered) s.materials[screen].emissiveTexture.texture = addTexture(s, 8, 8, checker(8, Vec3(0.f), Vec3(1.f)));
    s.cameras.push_back(lookAt({0.f, 0.4f, 2.6f}, {0.f, 0.5f, 0.f}, {0, 1, 0}, 1.1f));
    s.computeBounds();
    return s;
}

}  // namespace

// A screen that is half black emits half the power, and lights the floor like the untextured
// screen of half its strength: the emitted power (within 1 %), the emission the camera sees, and the
// light on the floor — by light sampling in the path tracer, and by direct photons in the
// splat — within 2 % (measured: 0.03 %, 0.1 %, 0.2 %, 0.2 %; the checker adds noise, not bias).
TEST(EmissiveTexture, CheckerHasTheMeanOfTheHalfStrengthEmitter) {
    const Scene checkered = screenOverFloor(true), half = screenOverFloor(false);
    EXPECT_NEAR(checkered.emittedPower().x, half.emittedPower().x, 0.01f * half.emittedPower().x);

    const RenderResult a = pathImage(checkered, 64, 32), b = pathImage(half, 64, 32);
    for (int layer : {kEmission, kDirect}) {
        const double ma = layerMean(a.film, layer), mb = layerMean(b.film, layer);
        EXPECT_GT(mb, 0.0) << layerName(layer);
        EXPECT_NEAR(ma, mb, 0.02 * mb) << layerName(layer) << " (path)";
    }

    RenderConfig cfg;
    cfg.output = "unused.exr";
    cfg.width = cfg.height = 32;
    cfg.spp = 4;
    cfg.passes = 1;
    cfg.grid = 64;
    cfg.voxelizer = "cpu";
    cfg.photons = 200000;
    cfg.direct = DirectMethod::Photons;
    cfg.threads = 2;
    const RenderResult pa = render(checkered, cfg, silentReporter()), pb = render(half, cfg, silentReporter());
    const double ma = layerMean(pa.film, kDirect), mb = layerMean(pb.film, kDirect);
    EXPECT_GT(mb, 0.0);
    EXPECT_NEAR(ma, mb, 0.02 * mb) << "direct photons (splat)";
}

// Light sampling of a textured emitter picks points by its texels; the density it reports for
// a point (pdfLi, what MIS weighs a BSDF-sampled hit with) is the one it drew the point with
// (up to the few points that rounding moves across a cell's edge), and the points it draws are
// brighter than the texture's mean 4: drawn by their radiance they would average 8·5/9 = 4.44
// on this bilinearly filtered checker (E[l²]/E[l] with l = (1−x)(1−y) + xy); measured 4.38.
TEST(EmissiveTexture, LightSamplingDensityMatchesItsDraws) {
    const Scene s = screenOverFloor(true);
    RayAccel accel(s, 1);
    LightSampler lights(s);
    const Vec3 p(0.3f, 0.f, -0.2f);
    const int n = 512;
    int mismatches = 0;
    double drawn = 0.0;
    for (uint32_t i = 0; i < uint32_t(n); ++i) {
        const LightSample ls = lights.sampleLi(p, 0.5f, sobol2D(i, 11));
        ASSERT_GT(ls.pdf, 0.f);
        SurfacePoint hit;
        float t;
        ASSERT_TRUE(accel.intersect(p + Vec3(0, 1e-4f, 0), ls.wi, kInf, hit, t));
        mismatches += std::abs(lights.pdfLi(p, hit.tri, hit.p) - ls.pdf) > 2e-3f * ls.pdf;
        drawn += luminance(ls.radiance);
    }
    EXPECT_LE(mismatches, n / 100);
    EXPECT_GT(drawn / n, 1.05 * 4.0);
}
