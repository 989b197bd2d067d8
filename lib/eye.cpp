#include "eye.h"

#include "accel.h"
#include "bsdf.h"
#include "camera.h"
#include "direct.h"
#include "log.h"
#include "parallel.h"
#include "sampling.h"

namespace rs {

namespace {

Vec2 octWrap(Vec2 v) {
    return (Vec2(1.f) - glm::abs(Vec2(v.y, v.x))) * Vec2(v.x >= 0.f ? 1.f : -1.f, v.y >= 0.f ? 1.f : -1.f);
}

uint32_t quantize(float x) { return uint32_t(std::lround(std::clamp(x * 0.5f + 0.5f, 0.f, 1.f) * 65535.f)); }

}  // namespace

uint32_t encodeUnit(const Vec3& n) {
    Vec3 a = glm::abs(n);
    float l1 = a.x + a.y + a.z;
    Vec2 p = l1 > 0.f ? Vec2(n.x, n.y) / l1 : Vec2(0.f);
    if (n.z < 0.f) p = octWrap(p);
    return quantize(p.x) | (quantize(p.y) << 16);
}

Vec3 decodeUnit(uint32_t e) {
    Vec2 p(float(e & 0xffffu) / 65535.f * 2.f - 1.f, float(e >> 16) / 65535.f * 2.f - 1.f);
    Vec3 n(p.x, p.y, 1.f - std::abs(p.x) - std::abs(p.y));
    float t = std::max(-n.z, 0.f);
    n.x += n.x >= 0.f ? -t : t;
    n.y += n.y >= 0.f ? -t : t;
    return glm::normalize(n);
}

size_t EyeSamples::bytes() const {
    return size() * (sizeof(Vec3) * 2 + sizeof(uint32_t) * 5 + sizeof(Vec2));
}

void EyeSamples::reserve(size_t n) {
    position.reserve(n);
    normal.reserve(n);
    geomNormal.reserve(n);
    toViewer.reserve(n);
    material.reserve(n);
    uv.reserve(n);
    pixel.reserve(n);
    weight.reserve(n);
}

void EyeSamples::append(const EyeSamples& o) {
    position.insert(position.end(), o.position.begin(), o.position.end());
    normal.insert(normal.end(), o.normal.begin(), o.normal.end());
    geomNormal.insert(geomNormal.end(), o.geomNormal.begin(), o.geomNormal.end());
    toViewer.insert(toViewer.end(), o.toViewer.begin(), o.toViewer.end());
    material.insert(material.end(), o.material.begin(), o.material.end());
    uv.insert(uv.end(), o.uv.begin(), o.uv.end());
    pixel.insert(pixel.end(), o.pixel.begin(), o.pixel.end());
    weight.insert(weight.end(), o.weight.begin(), o.weight.end());
}

template <class T>
static void permuteArray(std::vector<T>& v, const std::vector<uint32_t>& order) {
    std::vector<T> out(order.size());
    for (size_t i = 0; i < order.size(); ++i) out[i] = v[order[i]];
    v.swap(out);
}

void EyeSamples::permute(const std::vector<uint32_t>& order) {
    permuteArray(position, order);
    permuteArray(normal, order);
    permuteArray(geomNormal, order);
    permuteArray(toViewer, order);
    permuteArray(material, order);
    permuteArray(uv, order);
    permuteArray(pixel, order);
    permuteArray(weight, order);
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

}  // namespace

EyePass traceEyePass(const Scene& scene, const RayAccel& accel, const LightSampler* lights, const Camera& camera,
                     const EyePassSettings& st, ThreadPool& pool, Reporter& reporter) {
    const bool direct = st.directSamples > 0 && lights && !lights->empty();
    EyePass out;
    out.film = Film(st.width, st.height);
    CameraRays rays(camera, st.width, st.height);
    const float invSpp = 1.f / float(st.spp);
    std::vector<EyeSamples> rows(st.height);

    reporter.begin("eye pass", st.height, "rows");
    pool.parallelFor(st.height, 4, [&](int64_t y0, int64_t y1, int) {
        for (int64_t y = y0; y < y1; ++y) {
            EyeSamples& row = rows[y];
            row.reserve(size_t(st.width) * st.spp);
            for (int x = 0; x < st.width; ++x) {
                uint32_t pixel = uint32_t(y * st.width + x);
                uint64_t scramble = hashKey(st.seed, Stage::Camera, pixel);
                for (int s = 0; s < st.spp; ++s) {
                    const uint32_t index = uint32_t(st.firstSample + s);
                    Vec2 jitter = sobol2D(index, scramble);
                    Sampler sampler(st.seed, Stage::Eye, (uint64_t(pixel) << 24) ^ uint64_t(index));
                    Vec3 o = rays.origin(), d = rays.direction(Vec2(float(x), float(y)) + jitter);
                    Vec3 weight(invSpp);

                    // Follow the specular chain to the first non-specular surface.
                    for (int depth = 0; depth <= st.maxSpecularDepth; ++depth) {
                        SurfacePoint sp;
                        float t;
                        if (!accel.intersect(o, d, kInf, sp, t)) break;
                        const Material& m = scene.materials[sp.material];
                        if (m.isEmissive() && sp.frontFace) out.film.layers[kEmission][pixel] += weight * m.emission;
                        Vec3 wo = -d;
                        Bsdf bsdf(scene, sp, wo);
                        if (!bsdf.isDelta()) {
                            out.film.albedo[pixel] += invSpp * bsdf.albedo();
                            out.film.normal[pixel] += invSpp * bsdf.shadingNormal();
                            if (reflectsNothing(m)) break;
                            row.position.push_back(sp.p);
                            row.normal.push_back(encodeUnit(bsdf.shadingNormal()));
                            row.geomNormal.push_back(encodeUnit(glm::dot(sp.ng, wo) >= 0.f ? sp.ng : -sp.ng));
                            row.toViewer.push_back(encodeUnit(wo));
                            row.material.push_back(sp.material);
                            row.uv.push_back(sp.uv);
                            row.pixel.push_back(pixel);
                            row.weight.push_back(weight);
                            if (direct) {
                                const uint64_t key = (uint64_t(pixel) << 24) ^ uint64_t(index);
                                Sampler ds(st.seed, Stage::Direct, key);
                                Vec3 l = estimateDirect(accel, *lights, sp, bsdf, wo, st.directSamples,
                                                        hashKey(st.seed, Stage::Direct, key, 1), ds);
                                if (isFinite(l)) out.film.layers[kDirect][pixel] += weight * l;
                            }
                            break;
                        }
                        float uLobe = sampler.get1D();
                        BsdfSample bs = bsdf.sample(wo, uLobe, sampler.get2D(), Transport::Radiance);
                        if (bs.pdf <= 0.f || isBlack(bs.weight)) break;
                        weight *= bs.weight;
                        o = offsetRayOrigin(sp, bs.wi);
                        d = bs.wi;
                    }
                }
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
