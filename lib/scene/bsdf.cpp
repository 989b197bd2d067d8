// BSDFs of docs/design.md §3. The GGX lobe uses the Smith height-uncorrelated masking term and
// visible-normal sampling (Heitz 2018); Fresnel is Schlick's for conductors and the mix, exact
// for glass. Opaque materials are two-sided: the frame is turned to the side wo is on.
#include "scene/bsdf.h"

#include "core/sampling.h"

namespace rs {

namespace {

float schlickWeight(float cosTheta) {
    float m = std::clamp(1.f - cosTheta, 0.f, 1.f);
    return (m * m) * (m * m) * m;
}

Vec3 schlick(const Vec3& f0, float cosTheta) { return f0 + (Vec3(1.f) - f0) * schlickWeight(cosTheta); }

float ggxD(float cosH, float alpha) {
    float a2 = alpha * alpha;
    float c2 = cosH * cosH;
    float d = c2 * (a2 - 1.f) + 1.f;
    return a2 / (kPi * d * d);
}

float ggxLambda(float cosTheta, float alpha) {
    float c2 = cosTheta * cosTheta;
    if (c2 >= 1.f) return 0.f;
    float tan2 = (1.f - c2) / std::max(c2, 1e-12f);
    return 0.5f * (std::sqrt(1.f + alpha * alpha * tan2) - 1.f);
}
float ggxLambda(const Vec3& w, float alpha) { return ggxLambda(w.z, alpha); }

float ggxG1(float cosTheta, float alpha) { return 1.f / (1.f + ggxLambda(cosTheta, alpha)); }

Vec3 sampleGgxVisibleNormal(const Vec3& wo, float alpha, Vec2 u) {
    Vec3 vh = glm::normalize(Vec3(alpha * wo.x, alpha * wo.y, wo.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    Vec3 t1 = lensq > 0.f ? Vec3(-vh.y, vh.x, 0.f) / std::sqrt(lensq) : Vec3(1.f, 0.f, 0.f);
    Vec3 t2 = glm::cross(vh, t1);
    float r = std::sqrt(u.x), phi = 2.f * kPi * u.y;
    float p1 = r * std::cos(phi), p2 = r * std::sin(phi);
    float s = 0.5f * (1.f + vh.z);
    p2 = (1.f - s) * std::sqrt(std::max(0.f, 1.f - p1 * p1)) + s * p2;
    Vec3 nh = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.f, 1.f - p1 * p1 - p2 * p2)) * vh;
    return glm::normalize(Vec3(alpha * nh.x, alpha * nh.y, std::max(1e-6f, nh.z)));
}

Vec3 reflect(const Vec3& w, const Vec3& n) { return 2.f * glm::dot(w, n) * n - w; }

// The directional albedo of the mix's dielectric GGX layer (f0 = kDielectricF0), tabulated over
// cos θo and roughness = √α by integrating F·G2/G1 over visible normals on a fixed 32×32 grid:
// deterministic, computed once, on first use.
struct DielectricAlbedoTable {
    static constexpr int kCos = 64, kRough = 32, kGrid = 32;
    float e[kRough][kCos];
    DielectricAlbedoTable() {
        for (int r = 0; r < kRough; ++r) {
            const float alpha = std::max(sqr(float(r) / (kRough - 1)), 1e-4f);
            for (int c = 0; c < kCos; ++c) {
                const float cosO = std::max(float(c) / (kCos - 1), 1e-3f);
                const Vec3 wo(std::sqrt(1.f - cosO * cosO), 0.f, cosO);
                const float lambdaO = ggxLambda(wo, alpha);
                double sum = 0.0;
                for (int i = 0; i < kGrid; ++i)
                    for (int j = 0; j < kGrid; ++j) {
                        const Vec3 h = sampleGgxVisibleNormal(wo, alpha, Vec2((i + 0.5f) / kGrid, (j + 0.5f) / kGrid));
                        const Vec3 wi = reflect(wo, h);
                        if (wi.z <= 0.f) continue;
                        const float f = kDielectricF0 + (1.f - kDielectricF0) * schlickWeight(glm::dot(wo, h));
                        sum += f * (1.f + lambdaO) / (1.f + lambdaO + ggxLambda(wi, alpha));
                    }
                e[r][c] = float(sum / (kGrid * kGrid));
            }
        }
    }
};

}  // namespace

float dielectricLayerAlbedo(float cosO, float alpha) {
    static const DielectricAlbedoTable table;
    using T = DielectricAlbedoTable;
    const float x = std::clamp(cosO, 0.f, 1.f) * (T::kCos - 1), y = std::clamp(std::sqrt(alpha), 0.f, 1.f) * (T::kRough - 1);
    const int c = std::min(int(x), T::kCos - 2), r = std::min(int(y), T::kRough - 2);
    const float fx = x - c, fy = y - r;
    const float lo = glm::mix(table.e[r][c], table.e[r][c + 1], fx), hi = glm::mix(table.e[r + 1][c], table.e[r + 1][c + 1], fx);
    return glm::mix(lo, hi, fy);
}

GgxReflection ggxReflection(float cosO, float cosI, float cosH, float cosOH, float alpha) {
    float g = 1.f / (1.f + ggxLambda(cosO, alpha) + ggxLambda(cosI, alpha));
    return {ggxD(cosH, alpha) * g / (4.f * cosO * cosI), schlickWeight(cosOH)};
}

float fresnelDielectric(float cosThetaI, float eta) {
    float sin2T = (1.f - cosThetaI * cosThetaI) / (eta * eta);
    if (sin2T >= 1.f) return 1.f;
    float cosT = std::sqrt(1.f - sin2T);
    float rs = (cosThetaI - eta * cosT) / (cosThetaI + eta * cosT);
    float rp = (eta * cosThetaI - cosT) / (eta * cosThetaI + cosT);
    return 0.5f * (rs * rs + rp * rp);
}

Vec3 validSpecularNormal(const Vec3& ng, const Vec3& ns, const Vec3& wo) {
    const float cosGeometric = glm::dot(wo, ng);
    const float height = std::min(0.9f * cosGeometric, 0.01f);
    if (glm::dot(reflect(wo, ns), ng) >= height) return ns;
    // The normal n = √(1−s)·x + √s·ng, in the plane of ng and x (ns's direction along the
    // surface), reflects wo to the height 2(n·wo)(n·ng) − wo·ng. Setting that to `height` and
    // squaring gives a·s² − b·s + c/4 = 0; of its roots, the larger where wo leans against x
    // (wx < 0: 2·wx·√(s(1−s)) must then be negative), the smaller where it leans with it.
    const Vec3 along = ns - glm::dot(ns, ng) * ng;
    const float length = glm::length(along);
    if (!(length > 1e-6f)) return ng;
    const Vec3 x = along / length;
    const float wx = glm::dot(wo, x), wz = cosGeometric;
    const float a = wx * wx + wz * wz, b = a + wz * height, c = (height + wz) * (height + wz);
    const float root = std::sqrt(std::max(b * b - a * c, 0.f));
    const float s = std::clamp((wx < 0.f ? b + root : b - root) / (2.f * a), 0.f, 1.f);
    return std::sqrt(1.f - s) * x + std::sqrt(s) * ng;
}

Bsdf::Bsdf(const Scene& scene, const SurfacePoint& sp, const Vec3& wo)
    : material_(&scene.materials[sp.material]),
      albedo_(scene.albedo(sp.material, sp.attr, sp.footprint, sp.tri)),
      wo_(wo) {
    const Material& m = *material_;
    bool outside = glm::dot(wo, sp.ng) >= 0.f;
    ng_ = outside ? sp.ng : -sp.ng;
    Vec3 ns = outside ? sp.ns : -sp.ns;
    // An interpolated normal that puts wo below the surface would make light leak: use ng
    // there. A mapped one stays: its diffuse lobe does not depend on wo, and its GGX lobe takes
    // a normal that wo sees (specularNormal).
    const bool mapped = m.normalTexture.present() && !m.isSpecular();
    if (glm::dot(ns, ng_) <= 0.f || (!mapped && glm::dot(ns, wo) <= 1e-4f)) ns = ng_;
    frame_ = Frame(ns);
    bumped_ = mapped && ns != ng_;
    specularNormalOfWo_ = bumped_ ? validSpecularNormal(ng_, ns, wo) : ns;
    eta_ = outside ? m.ior : 1.f / m.ior;
    // Metallic and roughness at the point (the factors × the metallicRoughnessTexture).
    const Vec2 mr = m.metallicRoughnessTexture.present() ? scene.metallicRoughness(sp.material, sp.attr)
                                                         : Vec2(m.metallic, m.roughness);
    alpha_ = std::max(std::max(mr.y * mr.y, 1e-3f), 0.0025f);
    switch (m.kind) {
        case MaterialKind::Lambert: diffuseWeight_ = 1.f; break;
        case MaterialKind::Glossy: hasGgx_ = true; f0_ = albedo_; break;
        case MaterialKind::Mix:
            hasGgx_ = true;
            diffuseWeight_ = 1.f - mr.x;
            layered_ = true;
            f0_ = glm::mix(Vec3(kDielectricF0), albedo_, mr.x);
            break;
        case MaterialKind::Mirror: f0_ = albedo_; break;
        case MaterialKind::Glass: break;
    }
}

float Bsdf::diffuseScale(float cosO) const {
    return layered_ ? diffuseWeight_ * (1.f - dielectricLayerAlbedo(cosO, alpha_)) : diffuseWeight_;
}

float Bsdf::specularProbability(float cosO) const {
    if (!hasGgx_) return 0.f;
    if (diffuseWeight_ <= 0.f) return 1.f;
    float s = luminance(schlick(f0_, std::max(cosO, 0.f)));
    float d = diffuseWeight_ * luminance(albedo_);
    return std::clamp(s / std::max(s + d, 1e-6f), 0.05f, 0.95f);
}

Vec3 Bsdf::eval(const Vec3& woW, const Vec3& wiW) const {
    if (isDelta()) return Vec3(0.f);
    if (glm::dot(wiW, ng_) <= 0.f || glm::dot(woW, ng_) <= 0.f) return Vec3(0.f);  // opaque
    const Vec3& n = frame_.n;
    const Vec3 m = specularNormal(woW);
    const float cosI = glm::dot(wiW, n), cosO = glm::dot(woW, m);
    if (cosI <= 0.f || (!bumped_ && cosO <= 0.f)) return Vec3(0.f);
    Vec3 f = diffuseScale(cosO) * albedo_ * kInvPi * (bumped_ ? bumpShadowing(ng_, n, wiW) : 1.f);
    const float cosIm = bumped_ ? glm::dot(wiW, m) : cosI;
    if (hasGgx_ && cosO > 0.f && cosIm > 0.f) {
        const Vec3 h = glm::normalize(woW + wiW);
        const GgxReflection r = ggxReflection(cosO, cosIm, glm::dot(m, h), glm::dot(woW, h), alpha_);
        f += (f0_ + (Vec3(1.f) - f0_) * r.m5) * (r.dg * (cosIm / cosI));
    }
    return f;
}

float Bsdf::pdf(const Vec3& woW, const Vec3& wiW) const { return lobePdf(woW, wiW, frame_.n); }

float Bsdf::lobePdf(const Vec3& woW, const Vec3& wiW, const Vec3& diffuseNormal) const {
    if (isDelta()) return 0.f;
    if (glm::dot(wiW, ng_) <= 0.f || glm::dot(woW, ng_) <= 0.f) return 0.f;
    const Vec3 m = specularNormal(woW);
    const float cosO = glm::dot(woW, m), cosI = glm::dot(wiW, diffuseNormal);
    if (!bumped_ && (cosO <= 0.f || cosI <= 0.f)) return 0.f;
    const float ps = specularProbability(cosO);
    float p = (1.f - ps) * std::max(cosI, 0.f) * kInvPi;
    if (ps > 0.f && cosO > 0.f && glm::dot(wiW, m) > 0.f) {
        const Vec3 h = glm::normalize(woW + wiW);
        p += ps * ggxG1(cosO, alpha_) * ggxD(glm::dot(m, h), alpha_) / (4.f * cosO);
    }
    return p;
}

BsdfSample Bsdf::sample(const Vec3& woW, float uLobe, Vec2 u, Transport mode) const {
    BsdfSample s;
    Vec3 wo = frame_.toLocal(woW);
    const Material& m = *material_;

    if (m.kind == MaterialKind::Mirror) {
        s.wi = reflect(woW, frame_.n);
        s.weight = schlick(f0_, std::max(wo.z, 0.f));
        s.pdf = 1.f;
        s.delta = true;
        if (glm::dot(s.wi, ng_) <= 0.f) s.pdf = 0.f;
        return s;
    }
    if (m.kind == MaterialKind::Glass) {
        // Fresnel picks reflection or refraction; the chosen branch carries weight 1 (or the
        // transmission tint), so the estimator is unbiased for the sum of both.
        float cosI = std::max(wo.z, 0.f);
        float f = fresnelDielectric(cosI, eta_);
        s.delta = true;
        s.pdf = 1.f;
        if (uLobe < f) {
            s.wi = reflect(woW, frame_.n);
            s.weight = Vec3(1.f);
        } else {
            float sin2T = (1.f - cosI * cosI) / (eta_ * eta_);
            float cosT = std::sqrt(std::max(0.f, 1.f - sin2T));
            s.wi = glm::normalize(-woW / eta_ + (cosI / eta_ - cosT) * frame_.n);
            s.weight = albedo_ * (mode == Transport::Radiance ? 1.f / (eta_ * eta_) : 1.f);
        }
        return s;
    }
    const Vec3 lobeNormal = specularNormal(woW);
    const float cosO = glm::dot(woW, lobeNormal);
    if (cosO <= 0.f && !bumped_) return s;
    // A mapped normal's diffuse light leaves towards every direction above the geometric surface,
    // also those below the mapped normal (eval(wi, wo) does not depend on where wi is): a photon
    // leaving it is drawn around ng, which covers them all.
    const bool leavesAnyway = mode == Transport::Importance && bumped_;
    if (uLobe < specularProbability(cosO)) {
        if (cosO <= 0.f) return s;
        const Frame lobe = bumped_ ? Frame(lobeNormal) : frame_;
        const Vec3 wol = lobe.toLocal(woW);
        const Vec3 wi = reflect(wol, sampleGgxVisibleNormal(wol, alpha_, u));
        if (wi.z <= 0.f) return s;
        s.wi = lobe.toWorld(wi);
    } else {
        const Vec3 wi = sampleCosineHemisphere(u);
        if (wi.z <= 0.f) return s;
        s.wi = (leavesAnyway ? Frame(ng_) : frame_).toWorld(wi);
    }
    s.pdf = lobePdf(woW, s.wi, leavesAnyway ? ng_ : frame_.n);
    if (s.pdf <= 0.f) return s;
    if (mode == Transport::Radiance) {
        s.weight = eval(woW, s.wi) * (std::abs(glm::dot(s.wi, frame_.n)) / s.pdf);
        return s;
    }
    // A photon: woW is where its light comes from (eval's wi), and its flux arrives and leaves
    // per geometric area: f · |woW·ns| |wi·ng| / |woW·ng| / pdf (Veach 1997 §5.3, the adjoint
    // BSDF under a shading normal), which the camera's paths see as f · |wi·ns| / pdf.
    const float cosInGeometric = std::abs(glm::dot(woW, ng_));
    if (!(cosInGeometric > 0.f)) return s;
    s.weight = eval(s.wi, woW) * (std::abs(glm::dot(woW, frame_.n)) * std::abs(glm::dot(s.wi, ng_)) /
                                  (cosInGeometric * s.pdf));
    return s;
}

}  // namespace rs
