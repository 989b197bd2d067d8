#include "splat/eye.h"

#include "scene/accel.h"
#include "scene/bsdf.h"
#include "scene/camera.h"
#include "scene/direct.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/sampling.h"

namespace rs {

namespace {

Vec2 octWrap(Vec2 v) {
    return (Vec2(1.f) - glm::abs(Vec2(v.y, v.x))) * Vec2(v.x >= 0.f ? 1.f : -1.f, v.y >= 0.f ? 1.f : -1.f);
}

uint32_t quantize(float x) { return uint32_t(std::lround(std::clamp(x * 0.5f + 0.5f, 0.f, 1.f) * 65535.f)); }

}  // namespace

// The octahedral map's point p ∈ [−1, 1]² of a unit vector, and back.
static Vec2 octahedral(const Vec3& n) {
    Vec3 a = glm::abs(n);
    float l1 = a.x + a.y + a.z;
    Vec2 p = l1 > 0.f ? Vec2(n.x, n.y) / l1 : Vec2(0.f);
    return n.z < 0.f ? octWrap(p) : p;
}

static Vec3 fromOctahedral(Vec2 p) { return octahedralToUnit(p.x, p.y); }

uint32_t encodeUnit(const Vec3& n) {
    const Vec2 p = octahedral(n);
    return quantize(p.x) | (quantize(p.y) << 16);
}

Vec3 decodeUnit(uint32_t e) {
    return fromOctahedral(Vec2(float(e & 0xffffu) / 65535.f * 2.f - 1.f, float(e >> 16) / 65535.f * 2.f - 1.f));
}

// 255 levels a coordinate, so that 0 (and with it every axis-aligned normal) is exact.
uint16_t encodeUnit16(const Vec3& n) {
    const Vec2 p = octahedral(n);
    auto q = [](float x) { return uint32_t(std::lround(std::clamp(x * 0.5f + 0.5f, 0.f, 1.f) * 254.f)); };
    return uint16_t(q(p.x) | q(p.y) << 8);
}


uint32_t encodeRgb9e5(const Vec3& c) {
    const float r = std::clamp(c.x, 0.f, kMaxRgb9e5), g = std::clamp(c.y, 0.f, kMaxRgb9e5),
                b = std::clamp(c.z, 0.f, kMaxRgb9e5);
    const float m = std::max(r, std::max(g, b));  // NaN channels clamp to 0 above
    if (!(m > 0.f)) return 0;
    int exponent = std::max(-16, int(std::floor(std::log2(m)))) + 16;  // biased, m < 2^(exponent − 15)
    float scale = std::ldexp(1.f, 24 - exponent);
    if (std::lround(m * scale) > 511) ++exponent, scale *= 0.5f;
    exponent = std::min(exponent, 30);
    auto q = [&](float v) { return uint32_t(std::min(511l, std::lround(v * scale))); };
    return q(r) | q(g) << 9 | q(b) << 18 | uint32_t(exponent) << 27;
}

Vec3 EyeSamples::weightedF(size_t i, const Vec3& n, const Vec3& wi, float cosI) const {
    const uint32_t r = bsdf[i];
    return isGlossy(r) ? glossyF(r, n, wi, cosI) : decodeRgb9e5(r);
}

Vec3 EyeSamples::glossyF(uint32_t r, const Vec3& n, const Vec3& wi, float cosI) const {
    const GlossyLobe& lobe = lobes[lobeIndex(r)];
    Vec3 f = decodeRgb9e5(lobe.diffuse);
    const Vec3 wo = decodeUnit(lobe.toViewer);
    const float cosO = glm::dot(n, wo);
    if (cosO <= 0.f) return f;
    const Vec3 h = glm::normalize(wo + wi);
    const GgxReflection g = ggxReflection(cosO, cosI, glm::dot(n, h), glm::dot(wo, h), lobe.alpha);
    const Vec3 specular = decodeRgb9e5(lobe.specular), weight = decodeRgb9e5(lobe.weight);
    return f + (specular + (weight - specular) * g.m5) * g.dg;
}

void EyeSamples::add(const Vec3& p, const Vec3& ns, const Vec3& ng, uint32_t px, const Vec3& diffuse,
                     const GlossyLobe* lobe) {
    position.push_back(p);
    normal.push_back(encodeUnit16(ns));
    geomNormal.push_back(encodeUnit16(ng));
    pixel.push_back(px);
    if (!lobe) {
        bsdf.push_back(encodeRgb9e5(diffuse));
        return;
    }
    bsdf.push_back(kLobeFlag | uint32_t(lobes.size()));
    lobes.push_back(*lobe);
    lobes.back().diffuse = encodeRgb9e5(diffuse);
}

size_t EyeSamples::bytes() const {
    return size() * (sizeof(Vec3) + 2 * sizeof(uint16_t) + 2 * sizeof(uint32_t)) + lobes.size() * sizeof(GlossyLobe);
}

void EyeSamples::reserve(size_t n) {
    position.reserve(n);
    normal.reserve(n);
    geomNormal.reserve(n);
    pixel.reserve(n);
    bsdf.reserve(n);
}

void EyeSamples::append(const EyeSamples& o) {
    const uint32_t lobeBase = uint32_t(lobes.size());
    position.insert(position.end(), o.position.begin(), o.position.end());
    normal.insert(normal.end(), o.normal.begin(), o.normal.end());
    geomNormal.insert(geomNormal.end(), o.geomNormal.begin(), o.geomNormal.end());
    pixel.insert(pixel.end(), o.pixel.begin(), o.pixel.end());
    for (uint32_t r : o.bsdf) bsdf.push_back(isGlossy(r) ? kLobeFlag | (lobeIndex(r) + lobeBase) : r);
    lobes.insert(lobes.end(), o.lobes.begin(), o.lobes.end());
}

template <class T>
static void permuteArray(std::vector<T>& v, const std::vector<uint32_t>& order, ThreadPool& pool) {
    std::vector<T> out(order.size());
    pool.parallelFor(int64_t(order.size()), 1 << 16, [&](int64_t b, int64_t e, int) {
        for (int64_t i = b; i < e; ++i) out[size_t(i)] = v[order[size_t(i)]];
    });
    v.swap(out);
}

void EyeSamples::permute(const std::vector<uint32_t>& order, ThreadPool& pool) {
    permuteArray(position, order, pool);
    permuteArray(normal, order, pool);
    permuteArray(geomNormal, order, pool);
    permuteArray(pixel, order, pool);
    permuteArray(bsdf, order, pool);
}

}  // namespace rs

// -- The eye pass --------------------------------------------------------------------------

namespace rs {

namespace {

// A material that reflects nothing (the black base of an area light) receives no photon
// energy: no eye sample is stored for it.
bool reflectsNothing(const Material& m) {
    return m.kind == MaterialKind::Lambert && m.baseColorTexture < 0 && isBlack(m.baseColor);
}

// Follows a camera ray of weight `weight` through specular surfaces to the first non-specular
// one, adding the emitters met on the way (front faces) to `emission`; there calls
// atSurface(sp, bsdf, wo, weight). Returns without a call when the ray leaves the scene (adding
// the environment it sees, if any) or the chain ends.
template <class AtSurface>
void followCameraRay(const Scene& scene, const RayAccel& accel, const Environment* env, Vec3 o, Vec3 d, Vec3 weight,
                     int maxDepth, Sampler& sampler, Vec3& emission, AtSurface&& atSurface) {
    for (int depth = 0; depth <= maxDepth; ++depth) {
        SurfacePoint sp;
        float t;
        if (!accel.intersect(o, d, kInf, sp, t)) {
            if (env) emission += weight * env->radiance(d);
            return;
        }
        const Material& m = scene.materials[sp.material];
        if (m.isEmissive() && sp.frontFace) emission += weight * m.emission;
        const Vec3 wo = -d;
        Bsdf bsdf(scene, sp, wo);
        if (!bsdf.isDelta()) {
            atSurface(sp, bsdf, wo, weight);
            return;
        }
        const float uLobe = sampler.get1D();
        BsdfSample bs = bsdf.sample(wo, uLobe, sampler.get2D(), Transport::Radiance);
        if (bs.pdf <= 0.f || isBlack(bs.weight)) return;
        weight *= bs.weight;
        o = offsetRayOrigin(sp, bs.wi);
        d = bs.wi;
    }
}

// One pass's camera samples, pixel by pixel: the receivers (eye samples), and the direct film.
class EyePassTracer {
public:
    EyePassTracer(const Scene& scene, const RayAccel& accel, const LightSampler* lights, const Camera& camera,
                  const EyePassSettings& st, Film& film)
        : scene_(scene), accel_(accel), lights_(lights), rays_(camera, st.width, st.height), st_(st), film_(film),
          direct_(st.directSamples > 0 && lights && !lights->empty()), withFilm_(st.directSpp > 0) {}

    const Environment* environment() const { return lights_ ? lights_->environment() : nullptr; }

    // S camera samples, an eye sample each where the ray's specular chain ends. Without a
    // direct film they also take the emission, albedo, normal and direct light.
    void receivers(int x, int y, EyeSamples& row) const {
        const uint32_t pixel = pixelOf(x, y);
        const float invSpp = 1.f / float(st_.spp);
        const uint64_t scramble = hashKey(st_.seed, Stage::Camera, pixel);
        Vec3 unused(0.f);
        Vec3& emission = withFilm_ ? unused : film_.layers[kEmission][pixel];
        for (int s = 0; s < st_.spp; ++s) {
            const uint32_t index = uint32_t(st_.firstSample + s);
            Sampler sampler(st_.seed, Stage::Eye, pixelSampleKey(pixel, index));
            followCameraRay(scene_, accel_, environment(), rays_.origin(), rays_.direction(Vec2(float(x), float(y)) + sobol2D(index, scramble)),
                            Vec3(invSpp), st_.maxSpecularDepth, sampler, emission,
                            [&](const SurfacePoint& sp, const Bsdf& bsdf, const Vec3& wo, const Vec3& weight) {
                if (!withFilm_) addFeatures(pixel, invSpp, bsdf);
                if (reflectsNothing(scene_.materials[sp.material])) return;
                const Vec3 ng = glm::dot(sp.ng, wo) >= 0.f ? sp.ng : -sp.ng;
                const Vec3 diffuse = weight * bsdf.diffuseReflectance();
                if (bsdf.hasGlossyLobe()) {
                    GlossyLobe lobe{0, encodeRgb9e5(weight * bsdf.fresnelAtNormal()), encodeRgb9e5(weight), encodeUnit(wo),
                                    bsdf.ggxAlpha()};
                    row.add(sp.p, bsdf.shadingNormal(), ng, pixel, diffuse, &lobe);
                } else {
                    row.add(sp.p, bsdf.shadingNormal(), ng, pixel, diffuse);
                }
                if (!direct_ || withFilm_) return;
                const uint64_t key = pixelSampleKey(pixel, index);
                Sampler ds(st_.seed, Stage::Direct, key);
                addDirect(pixel, weight, estimateDirect(accel_, *lights_, sp, bsdf, wo, st_.directSamples,
                                                        hashKey(st_.seed, Stage::Direct, key, 1), ds));
            });
        }
    }

    // The direct film (docs/design.md §4): D camera samples of its own sequence, each with
    // emission, albedo, normal and direct light, the light samples of all the pixel's film
    // samples stratified as one sequence.
    void directFilm(int x, int y) const {
        if (!withFilm_) return;
        const uint32_t pixel = pixelOf(x, y);
        const float invFilm = 1.f / float(st_.directSpp);
        const uint64_t scramble = hashKey(st_.seed, Stage::DirectFilm, pixel);
        const uint64_t lightScramble = hashKey(st_.seed, Stage::DirectFilm, pixel, 1);
        for (int s = 0; s < st_.directSpp; ++s) {
            const uint32_t index = uint32_t(st_.firstDirectSample + s);
            const uint64_t key = pixelSampleKey(pixel, index) ^ (uint64_t(1) << 63);  // apart from the receivers'
            Sampler sampler(st_.seed, Stage::DirectFilm, key);
            followCameraRay(scene_, accel_, environment(), rays_.origin(), rays_.direction(Vec2(float(x), float(y)) + sobol2D(index, scramble)),
                            Vec3(invFilm), st_.maxSpecularDepth, sampler, film_.layers[kEmission][pixel],
                            [&](const SurfacePoint& sp, const Bsdf& bsdf, const Vec3& wo, const Vec3& weight) {
                addFeatures(pixel, invFilm, bsdf);
                if (!direct_ || reflectsNothing(scene_.materials[sp.material])) return;
                Sampler ds(st_.seed, Stage::Direct, key);
                addDirect(pixel, weight, estimateDirectAcrossSamples(accel_, *lights_, sp, bsdf, wo, st_.directSamples,
                                                                     lightScramble, index, ds));
            });
        }
    }

private:
    uint32_t pixelOf(int x, int y) const { return uint32_t(y * st_.width + x); }
    void addFeatures(uint32_t pixel, float weight, const Bsdf& bsdf) const {
        film_.albedo[pixel] += weight * bsdf.albedo();
        film_.normal[pixel] += weight * bsdf.shadingNormal();
    }
    void addDirect(uint32_t pixel, const Vec3& weight, const Vec3& l) const {
        if (isFinite(l)) film_.layers[kDirect][pixel] += weight * l;
    }

    const Scene& scene_;
    const RayAccel& accel_;
    const LightSampler* lights_;
    const CameraRays rays_;
    const EyePassSettings& st_;
    Film& film_;  // each pixel is written by the thread that owns its row only
    const bool direct_, withFilm_;
};

}  // namespace

EyePass traceEyePass(const Scene& scene, const RayAccel& accel, const LightSampler* lights, const Camera& camera,
                     const EyePassSettings& st, ThreadPool& pool, Reporter& reporter) {
    EyePass out;
    out.film = Film(st.width, st.height);
    const EyePassTracer tracer(scene, accel, lights, camera, st, out.film);
    std::vector<EyeSamples> rows(st.height);
    reporter.begin("eye pass", st.height, "rows");
    pool.parallelFor(st.height, 4, [&](int64_t y0, int64_t y1, int) {
        for (int64_t y = y0; y < y1; ++y) {
            EyeSamples& row = rows[y];
            row.reserve(size_t(st.width) * st.spp);
            for (int x = 0; x < st.width; ++x) {
                tracer.receivers(x, int(y), row);
                tracer.directFilm(x, int(y));
            }
            reporter.advance(1);
        }
    });
    reporter.end();

    size_t total = 0;
    for (const EyeSamples& r : rows) total += r.size();
    out.samples.reserve(total);
    for (EyeSamples& r : rows) {
        out.samples.append(r);
        r = EyeSamples();
    }
    return out;
}

}  // namespace rs
