#include "scene/direct.h"

#include "core/sampling.h"

namespace rs {

Vec3 sampleLightDirect(const RayAccel& accel, const LightSampler& lights, const SurfacePoint& sp, const Bsdf& bsdf,
                       const Vec3& wo, float uChoice, Vec2 u, bool mis) {
    LightSample ls = lights.sampleLi(sp.p, uChoice, u);
    if (!(ls.pdf > 0.f) || isBlack(ls.radiance)) return Vec3(0.f);
    Vec3 f = bsdf.eval(wo, ls.wi);
    float cosI = std::abs(glm::dot(ls.wi, bsdf.shadingNormal()));
    if (isBlack(f) || !(cosI > 0.f)) return Vec3(0.f);
    // Aim from the offset origin at the light point itself: along ls.wi, the offset would
    // carry the ray through the light's plane before tmax when the surface faces the light
    // at low elevation, and the light would shadow itself.
    Vec3 origin = offsetRayOrigin(sp, ls.wi);
    bool visible = std::isfinite(ls.dist) ? !accel.occluded(origin, sp.p + ls.wi * ls.dist - origin, 1.f - 1e-4f)
                                          : !accel.occluded(origin, ls.wi, kInf);
    if (!visible) return Vec3(0.f);
    float w = ls.delta || !mis ? 1.f : powerHeuristic(ls.pdf, bsdf.pdf(wo, ls.wi));
    return f * ls.radiance * (cosI * w / ls.pdf);
}

float emitterHitWeight(const LightSampler& lights, float bsdfPdf, const Vec3& from, const SurfacePoint& hit) {
    return powerHeuristic(bsdfPdf, lights.pdfLi(from, hit.tri, hit.p));
}

Vec3 environmentSeen(const LightSampler& lights, float bsdfPdf, const Vec3& dir) {
    const Environment* env = lights.environment();
    if (!env) return Vec3(0.f);
    const float w = bsdfPdf > 0.f ? powerHeuristic(bsdfPdf, lights.pdfEnvironment(dir)) : 1.f;
    return env->radiance(dir) * w;
}

namespace {

// n light samples, (uChoice, u) = lightNumbers(k), and n BSDF samples from `sampler`, MIS-combined.
template <class LightNumbers>
Vec3 directSamples(const RayAccel& accel, const LightSampler& lights, const SurfacePoint& sp, const Bsdf& bsdf,
                   const Vec3& wo, int n, Sampler& sampler, LightNumbers&& lightNumbers) {
    const Scene& scene = accel.scene();
    const bool mis = lights.wantsBsdfSamples(sp.p, bsdf.hasGlossyLobe());
    Vec3 sum(0.f);
    for (int k = 0; k < n; ++k) {
        float uChoice;
        Vec2 u;
        lightNumbers(k, uChoice, u);
        sum += sampleLightDirect(accel, lights, sp, bsdf, wo, std::min(uChoice, 0x1.fffffep-1f), u, mis);
        // BSDF sampling: emitted light met first by the sampled ray, where it is wanted.
        if (!mis) continue;
        float uLobe = sampler.get1D();
        BsdfSample bs = bsdf.sample(wo, uLobe, sampler.get2D(), Transport::Radiance);
        if (!(bs.pdf > 0.f) || isBlack(bs.weight) || bs.delta) continue;
        SurfacePoint hit;
        float t;
        if (!accel.intersect(offsetRayOrigin(sp, bs.wi), bs.wi, kInf, hit, t)) {
            sum += bs.weight * environmentSeen(lights, bs.pdf, bs.wi);
            continue;
        }
        const Material& m = scene.materials[hit.material];
        if (!m.isEmissive() || !hit.frontFace) continue;
        sum += bs.weight * scene.emissionAt(hit.material, hit.attr) * emitterHitWeight(lights, bs.pdf, sp.p, hit);
    }
    return sum / float(n);
}

}  // namespace

Vec3 estimateDirect(const RayAccel& accel, const LightSampler& lights, const SurfacePoint& sp, const Bsdf& bsdf,
                    const Vec3& wo, int n, uint64_t scramble, Sampler& sampler) {
    const float jitter = sampler.get1D();
    // Light sampling: stratified in the light choice and over the light's surface.
    return directSamples(accel, lights, sp, bsdf, wo, n, sampler, [&](int k, float& uChoice, Vec2& u) {
        u = sobol2D(uint32_t(k), scramble);
        uChoice = (float(k) + jitter) / float(n);
    });
}

Vec3 estimateDirectAcrossSamples(const RayAccel& accel, const LightSampler& lights, const SurfacePoint& sp,
                                 const Bsdf& bsdf, const Vec3& wo, int n, uint64_t scramble, uint32_t index,
                                 Sampler& sampler) {
    const uint32_t shuffle = uint32_t(scramble);
    const uint64_t pointScramble = mix64(scramble);
    return directSamples(accel, lights, sp, bsdf, wo, n, sampler, [&](int k, float& uChoice, Vec2& u) {
        // owenScramble of an index permutes it within aligned power-of-two blocks: any 2^m
        // consecutive samples still take 2^m consecutive points, in another order.
        const Vec2 p = sobol2D(owenScramble(index * uint32_t(n) + uint32_t(k), shuffle), pointScramble);
        uChoice = p.x;
        u = Vec2(lights.withinChoice(p.x), p.y);
    });
}

}  // namespace rs
