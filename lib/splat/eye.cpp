#include "splat/eye.h"

#include "scene/accel.h"
#include "scene/bsdf.h"
#include "scene/camera.h"
#include "scene/direct.h"
#include "scene/ray_cone.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/sampling.h"
#include "core/stats.h"

// -- The eye pass --------------------------------------------------------------------------

namespace rs {

namespace {

// A material that reflects nothing (the black base of an area light) receives no photon
// energy: no eye sample is stored for it.
bool reflectsNothing(const Material& m) {
    return m.kind == MaterialKind::Lambert && !m.baseColorTexture.present() && isBlack(m.baseColor);
}

// Follows a camera ray of weight `weight` (and footprint `cone`) through specular surfaces to the first non-specular
// one, adding the emitters met on the way (front faces) to `emission`; there calls
// atSurface(sp, bsdf, wo, weight). Returns without a call when the ray leaves the scene (adding
// the environment it sees, if any) or the chain ends.
template <class AtSurface>
void followCameraRay(const Scene& scene, const RayAccel& accel, const Environment* env, Vec3 o, Vec3 d, Vec3 weight,
                     RayCone cone, int maxDepth, Sampler& sampler, Vec3& emission, AtSurface&& atSurface) {
    for (int depth = 0; depth <= maxDepth; ++depth) {
        SurfacePoint sp;
        float t;
        if (!accel.intersect(o, d, kInf, sp, t)) {
            if (env) emission += weight * env->radiance(d);
            return;
        }
        cone.footprintAt(sp, t, d);
        const Material& m = scene.materials[sp.material];
        if (m.isEmissive() && sp.frontFace) emission += weight * scene.emissionAt(sp.material, sp.attr);
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
        cone = cone.scattered(t, bsdf);
        o = offsetRayOrigin(sp, bs.wi);
        d = bs.wi;
    }
}

// One pass's camera samples, pixel by pixel: the receivers (eye samples), and the direct film.
class EyePassTracer {
public:
    EyePassTracer(const Scene& scene, const RayAccel& accel, const LightSampler* lights, const Camera& camera,
                  const EyePassSettings& st, Film& film)
        : scene_(scene), accel_(accel), lights_(lights), rays_(camera, st.width, st.height),
          pixelCone_(RayCone::fromCamera(camera, st.height)), st_(st), film_(film),
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
            const Vec2 raster = Vec2(float(x), float(y)) + sobol2D(index, scramble);
            followCameraRay(scene_, accel_, environment(), rays_.origin(raster), rays_.direction(raster),
                            Vec3(invSpp), pixelCone_, st_.maxSpecularDepth, sampler, emission,
                            [&](const SurfacePoint& sp, const Bsdf& bsdf, const Vec3& wo, const Vec3& weight) {
                if (!withFilm_) addFeatures(pixel, invSpp, bsdf);
                if (reflectsNothing(scene_.materials[sp.material])) return;
                const Vec3 ng = glm::dot(sp.ng, wo) >= 0.f ? sp.ng : -sp.ng;
                const Vec3 diffuse = weight * bsdf.diffuseReflectance();
                if (bsdf.hasGlossyLobe()) {
                    GlossyLobe lobe{0, encodeRgb9e5(weight * bsdf.fresnelAtNormal()), encodeRgb9e5(weight), encodeUnit(wo),
                                    encodeUnit(bsdf.specularNormal(wo)), bsdf.ggxAlpha()};
                    row.add(sp.p, bsdf.shadingNormal(), ng, bsdf.bumped(), pixel, diffuse, &lobe);
                } else {
                    row.add(sp.p, bsdf.shadingNormal(), ng, bsdf.bumped(), pixel, diffuse);
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
    void directFilm(int x, int y, std::vector<Vec3>* noise, std::vector<float>* spread) const {
        if (!withFilm_) return;
        const uint32_t pixel = pixelOf(x, y);
        const int extra = st_.extraFilm ? int((*st_.extraFilm)[pixel]) : 0;
        // The light of the first and of the second half of the samples: each half of the pass's
        // block of the sequence is stratified by itself (even and odd ones are not: the even
        // ones of a Sobol sequence lie in the left half of the pixel).
        Vec3 halves[2] = {Vec3(0.f), Vec3(0.f)}, sum(0.f), squares(0.f);
        const float invFilm = 1.f / float(st_.directSpp + extra);
        const FilmSequence sequences[2] = {FilmSequence(st_.seed, pixel, 0), FilmSequence(st_.seed, pixel, 2)};
        const int pass = st_.firstDirectSample / st_.directSpp;
        for (int s = 0; s < st_.directSpp + extra; ++s) {
            const bool more = s >= st_.directSpp;  // a sample of the pixel's extra sequence
            const Vec3 before = noise || spread ? filmLight(pixel) : Vec3(0.f);
            if (more)
                filmSample(x, y, uint32_t(pass * FilmExtra::kExtraBlock + s - st_.directSpp), sequences[1], invFilm);
            else
                filmSample(x, y, uint32_t(st_.firstDirectSample + s), sequences[0], invFilm);
            if (!noise && !spread) continue;
            const Vec3 light = filmLight(pixel) - before;
            if (noise && !more) halves[2 * s >= st_.directSpp] += light;
            sum += light, squares += light * light;
        }
        if (noise && st_.directSpp >= 2) {
            const Vec3 d = halves[0] - halves[1];  // each half's mean is 2 × its sum
            (*noise)[pixel] = d * d;               // (2·Σfirst − 2·Σsecond)² / 4
        }
        if (spread && st_.directSpp >= 2 && extra == 0) {
            // A sample's light is D × what it added: its mean D·Σ/D, its variance D²·(Σ² − Σ²/D)/(D − 1).
            const float d = float(st_.directSpp);
            const Vec3 mean = sum, variance = glm::max(Vec3(0.f), (squares - sum * sum / d) * (d * d / (d - 1.f)));
            float s = 0.f;
            for (int c = 0; c < 3; ++c) s += variance[c] / (mean[c] * mean[c] + 0.01f);
            (*spread)[pixel] = std::sqrt(s);
        }
    }

    // One of a pixel's film sequences: 0, the passes' blocks of D; 2, the extra samples'. Its
    // camera points' and light points' scrambles, and the bit that keeps its keys apart.
    struct FilmSequence {
        FilmSequence(uint64_t seed, uint32_t pixel, uint64_t sequence)
            : scramble(hashKey(seed, Stage::DirectFilm, pixel, sequence)),
              lightScramble(hashKey(seed, Stage::DirectFilm, pixel, sequence + 1)),
              keyBits((uint64_t(1) << 63) ^ (sequence ? uint64_t(1) << 62 : 0)) {}
        uint64_t scramble, lightScramble;
        uint64_t keyBits;  // apart from the receivers' keys (bit 63), and the extra sequence's from the passes' (bit 62)
    };

    // One film sample of the pixel at (x, y): point `index` of `sequence`, weight `invFilm`.
    void filmSample(int x, int y, uint32_t index, const FilmSequence& sequence, float invFilm) const {
        const uint32_t pixel = pixelOf(x, y);
        const uint64_t scramble = sequence.scramble, lightScramble = sequence.lightScramble;
        const uint64_t key = pixelSampleKey(pixel, index) ^ sequence.keyBits;
        Sampler sampler(st_.seed, Stage::DirectFilm, key);
        const Vec2 raster = Vec2(float(x), float(y)) + sobol2D(index, scramble);
        followCameraRay(scene_, accel_, environment(), rays_.origin(raster), rays_.direction(raster),
                        Vec3(invFilm), pixelCone_, st_.maxSpecularDepth, sampler, film_.layers[kEmission][pixel],
                        [&](const SurfacePoint& sp, const Bsdf& bsdf, const Vec3& wo, const Vec3& weight) {
            addFeatures(pixel, invFilm, bsdf);
            if (!direct_ || reflectsNothing(scene_.materials[sp.material])) return;
            Sampler ds(st_.seed, Stage::Direct, key);
            addDirect(pixel, weight, estimateDirectAcrossSamples(accel_, *lights_, sp, bsdf, wo, st_.directSamples,
                                                                 lightScramble, index, ds));
        });
    }

private:
    uint32_t pixelOf(int x, int y) const { return uint32_t(y * st_.width + x); }
    Vec3 filmLight(uint32_t pixel) const { return film_.layers[kEmission][pixel] + film_.layers[kDirect][pixel]; }
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
    const RayCone pixelCone_;
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
    if (st.measureFilmNoise) out.filmNoise.assign(out.film.pixelCount(), Vec3(0.f));
    std::vector<Vec3>* noise = st.measureFilmNoise ? &out.filmNoise : nullptr;
    if (st.measureFilmSpread) out.filmSpread.assign(out.film.pixelCount(), 0.f);
    std::vector<float>* spread = st.measureFilmSpread ? &out.filmSpread : nullptr;
    std::vector<EyeSamples> rows(st.height);
    reporter.begin("eye pass", st.height, "rows");
    pool.parallelFor(st.height, 4, [&](int64_t y0, int64_t y1, int) {
        for (int64_t y = y0; y < y1; ++y) {
            EyeSamples& row = rows[y];
            row.reserve(size_t(st.width) * st.spp);
            for (int x = 0; x < st.width; ++x) {
                tracer.receivers(x, int(y), row);
                tracer.directFilm(x, int(y), noise, spread);
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

EyePassCost estimateEyePass(const Scene& scene, const RayAccel& accel, const LightSampler* lights, const Camera& camera,
                            const EyePassSettings& st, ThreadPool& pool) {
    EyePassSettings pilot = st;
    pilot.measureFilmNoise = pilot.measureFilmSpread = false;
    Film film(st.width, st.height);
    const EyePassTracer tracer(scene, accel, lights, camera, pilot, film);
    const int rows = (st.height + EyePassCost::kPilotRows - 1) / EyePassCost::kPilotRows;
    std::vector<double> parts(size_t(pool.size()) * 2, 0.0);  // per thread: receivers', film's seconds
    Timer wall;
    pool.parallelFor(rows, 1, [&](int64_t r0, int64_t r1, int thread) {
        EyeSamples row;
        for (int64_t r = r0; r < r1; ++r) {
            const int y = int(r) * EyePassCost::kPilotRows;
            for (int x = 0; x < st.width; ++x) {
                Timer t;
                tracer.receivers(x, y, row);
                const double between = t.seconds();
                tracer.directFilm(x, y, nullptr, nullptr);
                parts[size_t(thread) * 2] += between;
                parts[size_t(thread) * 2 + 1] += t.seconds() - between;
            }
            row = EyeSamples();
        }
    });
    double receivers = 0.0, filmPart = 0.0;
    for (size_t i = 0; i < parts.size(); i += 2) receivers += parts[i], filmPart += parts[i + 1];
    EyePassCost cost;
    const double whole = wall.seconds() * double(st.height) / double(rows), busy = receivers + filmPart;
    if (busy > 0.0) cost.receivers = whole * receivers / busy, cost.film = whole * filmPart / busy;
    return cost;
}

EyePassSize eyePassWithin(const EyePassCost& cost, double budget, int spp, int directSpp) {
    EyePassSize size{spp, directSpp};
    const auto fits = [&] {
        return cost.receivers * size.spp / std::max(spp, 1) + cost.film * size.directSpp / std::max(directSpp, 1) <= budget;
    };
    const auto powerBelow = [](int n) { return 1 << int(std::floor(std::log2(double(n - 1)))); };
    if (directSpp > 2 && !fits())
        for (size.directSpp = powerBelow(directSpp); size.directSpp > 2 && !fits();) size.directSpp /= 2;
    if (spp > 1 && !fits())
        for (size.spp = powerBelow(spp); size.spp > 1 && !fits();) size.spp /= 2;
    return size;
}

std::vector<uint16_t> filmExtraSamples(const std::vector<float>& spread, int directSpp, double* removed) {
    std::vector<uint16_t> extra(spread.size(), 0);
    double total = 0.0;
    for (float s : spread) total += double(s);
    if (!(total > 0.0) || directSpp <= 0) return extra;
    // n_p = max(D, spread_p / λ) (Neyman's allocation above the D every pixel takes), with λ·D
    // the mean spread times kSpreadOverMean: a film whose light is spread evenly takes none.
    const double threshold = FilmExtra::kSpreadOverMean * total / double(spread.size());
    const double most = std::min<double>((FilmExtra::kExtraMultiple - 1) * directSpp, FilmExtra::kExtraBlock);
    std::vector<double> want(spread.size(), 0.0);
    double wanted = 0.0;
    for (size_t p = 0; p < spread.size(); ++p) {
        want[p] = std::min(most, std::max(0.0, double(directSpp) * (double(spread[p]) / threshold - 1.0)));
        wanted += want[p];
    }
    const double budget = FilmExtra::kExtraShare * double(directSpp) * double(spread.size());
    const double scale = wanted > budget ? budget / wanted : 1.0;
    double variance = 0.0, gone = 0.0, samples = 0.0;
    const double d = double(directSpp);
    for (size_t p = 0; p < spread.size(); ++p) {
        extra[p] = uint16_t(std::floor(want[p] * scale));
        const double v = double(spread[p]) * spread[p];
        variance += v / d;
        gone += v * (1.0 / d - 1.0 / (d + extra[p]));
        samples += extra[p];
    }
    if (removed) {
        removed[0] = variance > 0.0 ? gone / variance : 0.0;
        removed[1] = samples / (d * double(spread.size()));
    }
    return extra;
}

}  // namespace rs
