// Scattering at a surface point for every material kind of docs/design.md §3: Lambert, GGX
// conductor, the Lambert+GGX mix, smooth glass and the perfect mirror. Directions are
// world-space unit vectors pointing away from the surface (wo to the viewer or the previous
// vertex, wi to the light or the next vertex). Values are f(wo, wi) without the cosine.
#pragma once

#include "scene/accel.h"
#include "core/math.h"

namespace rs {

// Radiance: camera paths (refraction scales radiance by 1/η²); Importance: photon paths,
// which carry flux and do not scale.
enum class Transport { Radiance, Importance };

struct BsdfSample {
    Vec3 wi{0.f};
    Vec3 weight{0.f};  // f·|cos θi| / pdf  (the Fresnel-chosen branch weight for delta lobes)
    float pdf = 0.f;   // solid angle; 0 when the sample failed
    bool delta = false;
};

// A normal-mapped GGX lobe's normal seen from wo (Cycles' reading of a bump-mapped specular
// normal): the mapped normal ns where the mirror reflection of wo about it leaves above the
// geometric surface by min(0.9·(wo·ng), 0.01) at least; else ns bent towards ng, in their plane,
// until that reflection leaves at exactly that height. A normal map tilted away from the viewer
// then keeps a highlight rather than reflecting into the surface. ng, ns, wo unit, on one side.
Vec3 validSpecularNormal(const Vec3& ng, const Vec3& ns, const Vec3& wo);

class Bsdf {
public:
    // wo: unit direction away from the surface towards the previous vertex.
    Bsdf(const Scene& scene, const SurfacePoint& sp, const Vec3& wo);

    bool isDelta() const { return material_->isSpecular(); }
    // 0 for delta materials. Where a normal map gives the GGX lobe a normal of its own
    // (specularNormal), that lobe's term is scaled by (wi·its normal) / (wi·shadingNormal()), so
    // that eval × |wi·shadingNormal()| is each lobe's f times its own cosine, as every caller
    // takes it; light below the shading normal then reaches neither lobe.
    Vec3 eval(const Vec3& wo, const Vec3& wi) const;
    float pdf(const Vec3& wo, const Vec3& wi) const;  // 0 for delta materials
    // u: one number picks the lobe (or the Fresnel branch), two more the direction.
    BsdfSample sample(const Vec3& wo, float uLobe, Vec2 u, Transport mode) const;
    Vec3 albedo() const { return albedo_; }
    // The parts eval() is made of, for eye samples that store them (eye.h's GlossyLobe).
    // The diffuse lobe's f towards the wo of the constructor (the viewer, for eye samples).
    Vec3 diffuseReflectance() const { return diffuseScale(glm::dot(specularNormalOfWo_, wo_)) * albedo_ * kInvPi; }
    bool hasGlossyLobe() const { return hasGgx_; }
    Vec3 fresnelAtNormal() const { return f0_; }
    float ggxAlpha() const { return alpha_; }
    const Vec3& shadingNormal() const { return frame_.n; }
    // The GGX lobe's normal seen from wo: the shading normal, but where a normal map bent it
    // (validSpecularNormal; made once for the constructor's wo, which eval, pdf and sample see
    // but for a photon's way out).
    Vec3 specularNormal(const Vec3& wo) const {
        return !bumped_ || wo == wo_ ? specularNormalOfWo_ : validSpecularNormal(ng_, frame_.n, wo);
    }
    // Whether a normal map bends the shading normal: only then does the diffuse lobe take
    // bumpShadowing (interpolated normals alone do not, as in Cycles and Mitsuba), and the GGX
    // lobe a normal of its own.
    bool bumped() const { return bumped_; }

private:
    // cosO: wo's cosine to the GGX lobe's normal.
    float specularProbability(float cosO) const;
    // pdf() of sample() with its diffuse lobe drawn around diffuseNormal.
    float lobePdf(const Vec3& wo, const Vec3& wi, const Vec3& diffuseNormal) const;
    // The diffuse lobe's weight seen from a direction of cosine cosO to the shading normal:
    // (1 − metallic), under the mix's dielectric layer times 1 − that layer's albedo.
    float diffuseScale(float cosO) const;

    const Material* material_;
    Frame frame_;      // around the shading normal, flipped to wo's side for opaque materials;
                       // a mapped one (bumped_) may face away from wo: only the GGX lobe needs wo
    Vec3 ng_;          // geometric normal, same side as frame_.n for opaque materials
    Vec3 albedo_;      // base colour at the point
    Vec3 f0_;          // Fresnel at normal incidence of the GGX / mirror lobe
    Vec3 wo_;          // the constructor's wo
    Vec3 specularNormalOfWo_;  // specularNormal(wo_)
    float diffuseWeight_ = 0.f;  // (1 − metallic) for Lambert and mix
    bool hasGgx_ = false;
    bool layered_ = false;  // the mix: a diffuse lobe under a dielectric GGX layer
    bool bumped_ = false;
    float alpha_ = 1.f;
    float eta_ = 1.f;  // glass: ηt/ηi for light leaving towards the side opposite wo
};

// The GGX lobe of eval(): with cosines to the shading normal of wo, wi (both > 0) and of the
// half vector h, and wo·h, f = schlick(f0, wo·h) · dg, schlick(f0, c) = f0 + (1 − f0)·m5.
struct GgxReflection {
    float dg = 0.f;  // D(h)·G(wo, wi) / (4 cosθo cosθi)
    float m5 = 0.f;  // (1 − wo·h)^5
};

// Fresnel at normal incidence of the mix's dielectric layer (glTF's IOR 1.5).
constexpr float kDielectricF0 = 0.04f;
// The directional albedo E(cos θo) of that layer, a GGX lobe of roughness² = alpha with Schlick's
// Fresnel of f0 = kDielectricF0: what it reflects of light arriving from all of the hemisphere.
// The diffuse lobe under it is weighed by 1 − E(cos θo) (albedo scaling, as Blender's Principled
// BSDF layers it): a white mix reflects all it receives, at every angle.
float dielectricLayerAlbedo(float cosO, float alpha);

// The diffuse lobe's share of light from wi on a surface whose shading normal ns leans from its
// geometric normal ng (normal maps): the shadowing of Chiang, Li & Burley 2019, "Taming the
// Shadow Terminator", g = (ng·wi) / ((ns·wi)(ng·ns)) in [0, 1], smoothed to −g³ + g² + g. A bumpy
// surface lit at a grazing angle shadows part of itself; without it a normal map tilted towards
// the light reflects more than the surface receives. 1 where ns = ng; ng, ns on wi's side.
// Applied where a normal map bends the normal (Bsdf::bumped), not to interpolated normals.
inline float bumpShadowing(const Vec3& ng, const Vec3& ns, const Vec3& wi) {
    if (ns == ng) return 1.f;
    const float g = glm::dot(ng, wi) / std::max(glm::dot(ns, wi) * glm::dot(ng, ns), 1e-12f);
    if (g >= 1.f) return 1.f;
    if (!(g > 0.f)) return 0.f;
    return g * (1.f + g - g * g);
}
GgxReflection ggxReflection(float cosO, float cosI, float cosH, float cosOH, float alpha);

// Exact dielectric Fresnel reflectance for cosθi (≥ 0) and relative IOR eta = ηt/ηi.
float fresnelDielectric(float cosThetaI, float eta);

}  // namespace rs
