#include "path/path.h"

#include <algorithm>

#include "scene/bsdf.h"
#include "scene/camera.h"
#include "scene/direct.h"
#include "scene/ray_cone.h"
#include "core/sampling.h"

namespace rs {

namespace {

// Which film layer light belongs to, from where the path is relative to its first
// non-specular vertex y (the eye sample's vertex of the splat method).
struct PathClass {
    bool pastFirstDiffuse = false;  // y has been reached
    bool nonSpecularAfter = false;  // a non-specular vertex beyond y
    bool atFirstDiffuse = false;    // the current vertex is y

    // Light arriving at the current vertex by next-event estimation.
    int layerOfLightSample() const {
        if (!pastFirstDiffuse) return kEmission;
        return atFirstDiffuse ? kDirect : kIndirect;
    }
    // An emitter hit by the ray leaving the current vertex.
    int layerOfHit() const {
        if (!pastFirstDiffuse) return kEmission;
        if (nonSpecularAfter) return kIndirect;
        return atFirstDiffuse ? kDirect : kCaustic;
    }
};

}  // namespace

PathRadiance tracePath(const Scene& scene, const RayAccel& accel, const LightSampler& lights, Vec3 o, Vec3 d,
                       int maxDepth, Sampler& sampler) {
    return tracePath(scene, accel, lights, o, d, maxDepth, sampler, RayCone());
}

PathRadiance tracePath(const Scene& scene, const RayAccel& accel, const LightSampler& lights, Vec3 o, Vec3 d,
                       int maxDepth, Sampler& sampler, RayCone cone) {
    PathRadiance out;
    Vec3 beta(1.f);
    PathClass cls;
    bool prevDelta = true;
    float prevPdf = 0.f;
    Vec3 prevP = o;

    for (int depth = 0; depth < maxDepth; ++depth) {
        SurfacePoint sp;
        float t;
        if (!accel.intersect(o, d, kInf, sp, t)) {
            // The environment: MIS against the light sampling of the previous vertex.
            out.layer[cls.layerOfHit()] += beta * environmentSeen(lights, prevDelta ? 0.f : prevPdf, d);
            break;
        }
        cone.footprintAt(sp, t, d);
        const Material& m = scene.materials[sp.material];

        // Emitters: front face only; MIS against the light sampling of the previous vertex.
        if (m.isEmissive() && sp.frontFace) {
            float w = 1.f;
            if (!prevDelta) w = emitterHitWeight(lights, prevPdf, prevP, sp);
            out.layer[cls.layerOfHit()] += beta * scene.emissionAt(sp.material, sp.attr) * w;
        }

        Vec3 wo = -d;
        Bsdf bsdf(scene, sp, wo);
        bool delta = bsdf.isDelta();
        // Bookkeeping of the path's class at this vertex.
        if (cls.pastFirstDiffuse) {
            cls.atFirstDiffuse = false;
            if (!delta) cls.nonSpecularAfter = true;
        } else if (!delta) {
            cls.pastFirstDiffuse = true;
            cls.atFirstDiffuse = true;
            out.albedo = bsdf.albedo();
            out.normal = bsdf.shadingNormal();
        }

        // Next-event estimation.
        if (!delta && !lights.empty()) {
            float uc = sampler.get1D();
            Vec2 ul = sampler.get2D();
            out.layer[cls.layerOfLightSample()] += beta * sampleLightDirect(accel, lights, sp, bsdf, wo, uc, ul);
        } else {
            sampler.get1D();  // keep the dimension count per depth fixed
            sampler.get2D();
        }

        // Continue the path by sampling the BSDF.
        float ulobe = sampler.get1D();
        Vec2 ud = sampler.get2D();
        BsdfSample bs = bsdf.sample(wo, ulobe, ud, Transport::Radiance);
        if (bs.pdf <= 0.f || isBlack(bs.weight)) break;
        beta *= bs.weight;
        prevDelta = bs.delta;
        prevPdf = bs.pdf;
        prevP = sp.p;
        cone = cone.scattered(t, bsdf);
        o = offsetRayOrigin(sp, bs.wi);
        d = bs.wi;

        // Russian roulette once the path has a few vertices.
        float urr = sampler.get1D();
        if (depth >= 3) {
            float q = std::min(0.95f, maxComponent(beta));
            if (urr >= q) break;
            beta /= q;
        }
    }
    return out;
}

Film renderPathPass(const Scene& scene, const RayAccel& accel, const LightSampler& lights, const Camera& camera,
                    const PathSettings& pass, ThreadPool& pool, Reporter& reporter) {
    const int width = pass.width, height = pass.height;
    Film film(width, height);
    CameraRays rays(camera, width, height);
    const RayCone pixelCone = RayCone::fromCamera(camera, height);
    const float invSpp = 1.f / float(pass.spp);
    const int rowBegin = std::clamp(pass.rowBegin, 0, height);
    const int rowEnd = pass.rowEnd > 0 ? std::clamp(pass.rowEnd, rowBegin, height) : height;
    reporter.begin("path tracing", rowEnd - rowBegin, "rows");
    pool.parallelFor(rowEnd - rowBegin, 1, [&](int64_t y0, int64_t y1, int) {
        for (int64_t y = rowBegin + y0; y < rowBegin + y1; ++y) {
            for (int x = 0; x < width; ++x) {
                size_t pixel = size_t(y) * width + x;
                uint64_t scramble = hashKey(pass.seed, Stage::Camera, pixel);
                for (int s = 0; s < pass.spp; ++s) {
                    uint32_t index = uint32_t(pass.firstSample + s);
                    const Vec2 raster = Vec2(float(x), float(y)) + sobol2D(index, scramble);
                    Sampler sampler(pass.seed, Stage::Path, pixelSampleKey(pixel, index));
                    PathRadiance r = tracePath(scene, accel, lights, rays.origin(raster), rays.direction(raster),
                                               pass.maxDepth, sampler, pixelCone);
                    for (int l = 0; l < kLayerCount; ++l) {
                        Vec3 v = r.layer[l];
                        if (isFinite(v)) film.layers[l][pixel] += v * invSpp;  // one NaN must not poison a pixel
                    }
                    film.albedo[pixel] += r.albedo * invSpp;
                    film.normal[pixel] += r.normal * invSpp;
                }
            }
            reporter.advance(1);
        }
    });
    reporter.end();
    return film;
}

}  // namespace rs
