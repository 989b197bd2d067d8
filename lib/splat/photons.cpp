// Photon tracer. Paths are traced in blocks of a fixed size, in parallel; each block's
// photons are then merged in path order against the class quotas. The merge and the
// decisions it drives (which classes are still open, early path termination) happen only at
// block boundaries, so the result does not depend on the thread count.
//
// Splat radius (docs/design.md §7): aim for k photons of the same class under the kernel,
// π h² N_c p⊥ = k, with p⊥ the density per unit perpendicular area with which one path puts
// a photon near x(i): the light's choice probability × the solid-angle pdf of the last sampled
// direction / the squared length since that vertex (specular bounces keep the pdf and add
// length), × the Russian-roulette survival of the path so far. Collimated (directional)
// light has p⊥ = choice / (π r²) of its emission disc. Clamped to [min, max] voxels, then
// scaled by the pass's shrinkage (the clamps shrink with the kernels).
#include "splat/photons.h"

#include "scene/accel.h"
#include "scene/bsdf.h"
#include "scene/ray_cone.h"
#include "core/stats.h"
#include "core/error.h"
#include "splat/eye.h"
#include "scene/lights.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/qmc.h"

namespace rs {

float PhotonRay::reachOf(float cosTheta) {
    constexpr float kMaxReach = 16.f;  // θ up to 86.4°; beyond, grazing rays lose the rest
    float c = std::abs(cosTheta);
    if (!(c * kMaxReach > std::sqrt(std::max(0.f, 1.f - c * c)))) return kMaxReach;
    return std::max(1.f, std::sqrt(std::max(0.f, 1.f - c * c)) / c);
}

const char* photonClassName(int c) {
    static const char* names[kPhotonClassCount] = {"direct", "indirect", "caustic"};
    return names[c];
}

namespace {

// How far o + t·d runs before it leaves the box (0 when it starts outside).
float exitDistance(const Bounds3& b, const Vec3& o, const Vec3& d) {
    float t = kInf;
    for (int a = 0; a < 3; ++a)
        if (d[a] != 0.f) t = std::min(t, ((d[a] > 0.f ? b.hi[a] : b.lo[a]) - o[a]) / d[a]);
    return std::max(t, 0.f);
}

// With reachToBounds: the kernel reaches on to a radius past the scene's bounds.
void reachBounds(const Scene& scene, PhotonRay& r) {
    if (r.radius > 0.f) r.reach = std::max(r.reach, (exitDistance(scene.bounds, r.origin, r.dir) - r.length) / r.radius + 1.f);
}

constexpr int64_t kBlockPaths = 8192;  // paths per merge block (fixed: determinism)
constexpr int64_t kProbePaths = 32768;  // the first block, whose yield sets the quotas
constexpr int kDimsPerBounce = 4;      // lobe, direction (2), Russian roulette

struct Traced {
    PhotonRay ray;
    uint32_t path;  // index within the block
};

// Traces path `n`; appends its photon rays. `open` says which classes are still wanted, so
// that a path that can no longer produce one stops early.
void tracePath(const Scene& scene, const RayAccel& accel, const LightSampler& lights, const ScrambledHalton& qmc,
               const PhotonSettings& st, uint64_t n, const bool open[kPhotonClassCount], std::vector<PhotonRay>& out) {
    auto u = [&](int dim) { return qmc.sample(n - st.firstPath, dim); };
    // Dimensions 0–2 drawn only where they are read (one point light: neither).
    const float uChoice = lights.emissionChooses() ? u(0) : 0.f;
    const Vec2 uPos = lights.emissionPlaces() ? Vec2(u(1), u(2)) : Vec2(0.f);
    EmissionSample e = lights.sampleEmission(uChoice, uPos, {u(3), u(4)});
    if (!(e.choiceProb > 0.f) || isBlack(e.flux)) return;

    Vec3 flux = e.flux, o = e.origin, d = e.dir;
    if (glm::dot(e.normal, e.normal) > 0.f) {  // leave the emitter's surface, like any ray origin
        SurfacePoint onLight;
        onLight.p = e.origin;
        onLight.ng = e.normal;
        o = offsetRayOrigin(onLight, d);
    }
    Vec3 originNormal = e.normal;
    RayCone cone = RayCone::fromLight();
    float lastPdf = e.pdfDir;          // solid-angle pdf of the last sampled direction
    float lengthSince = 0.f;           // path length since that vertex
    float prefix = e.choiceProb;       // probability of the prefix (choice × RR survival)
    bool collimated = e.collimated;
    bool specularOnly = true;          // no non-specular vertex yet
    float collimatedDensity = collimated ? e.pdfChoicePos / e.choiceProb : 0.f;

    for (int depth = 0; depth < st.maxDepth; ++depth) {
        // Nothing this path can still produce is wanted: stop.
        bool canDirect = depth == 0 && open[kPhotonDirect];
        bool canCaustic = specularOnly && open[kPhotonCaustic];
        if (!canDirect && !canCaustic && !open[kPhotonIndirect]) return;

        SurfacePoint sp;
        float t;
        if (!accel.intersect(o, d, kInf, sp, t)) return;
        lengthSince += t;
        cone.footprintAt(sp, t, d);
        Bsdf bsdf(scene, sp, -d);
        if (!bsdf.isDelta()) {
            PhotonRay r;
            r.origin = o;
            r.dir = d;
            r.length = t;
            r.flux = flux;
            r.originNormal = glm::dot(originNormal, originNormal) > 0.f ? encodeUnit(originNormal) : 0u;
            r.reach = PhotonRay::reachOf(glm::dot(sp.ng, d));
            r.cls = depth == 0 ? kPhotonDirect : specularOnly ? kPhotonCaustic : kPhotonIndirect;
            r.density = collimated ? prefix * collimatedDensity : prefix * lastPdf / std::max(sqr(lengthSince), 1e-12f);
            r.radius = 0.f;
            r.path = uint32_t(n - st.firstPath);
            if (open[r.cls]) out.push_back(r);
        }

        // Scatter.
        int base = 5 + depth * kDimsPerBounce;
        BsdfSample bs = bsdf.sample(-d, u(base), {u(base + 1), u(base + 2)}, Transport::Importance);
        if (bs.pdf <= 0.f || isBlack(bs.weight)) return;
        Vec3 next = flux * bs.weight;
        // Russian roulette keeps the photon's flux roughly constant.
        float q = std::min(1.f, maxComponent(next) / std::max(maxComponent(flux), 1e-30f));
        if (depth >= 1 && q < 1.f) {
            if (u(base + 3) >= q) return;
            next /= q;
            prefix *= q;
        }
        flux = next;
        if (!bs.delta) {
            specularOnly = false;
            collimated = false;
            lastPdf = bs.pdf;
            lengthSince = 0.f;
        }
        originNormal = glm::dot(bs.wi, sp.ng) >= 0.f ? sp.ng : -sp.ng;
        cone = cone.scattered(t, bsdf);
        o = offsetRayOrigin(sp, bs.wi);
        d = bs.wi;
    }
}

// A class that the probe shows cannot be filled within maxPaths (no glass: no caustics, or a
// little glass that few paths reach) keeps what it can get within a share of the paths and
// hands the rest of its quota to the others, by their split. The share: half the path budget,
// and no more than kRareClassPaths times the paths the fillable classes need. On the staircase
// interior the caustics' 4 % of the photons took 2.2 M paths, 90 % of the photon tracing, for
// 1 % of the image's error; their 500 within the bound render with the same error.
constexpr double kRareClassPaths = 16.0;
void rebalanceQuotas(const std::vector<std::vector<PhotonRay>>& probe, int64_t maxPaths, const PhotonSettings& st,
                     int64_t quota[kPhotonClassCount], bool open[kPhotonClassCount]) {
    int64_t yield[kPhotonClassCount] = {};
    for (const auto& path : probe)
        for (const PhotonRay& r : path) yield[r.cls]++;
    int64_t spare = 0;
    bool fillable[kPhotonClassCount];
    double needed = 0.0;  // paths the fillable classes need
    for (int c = 0; c < kPhotonClassCount; ++c) {
        fillable[c] = open[c] && double(yield[c]) * double(maxPaths) / double(probe.size()) >= double(quota[c]);
        if (fillable[c]) needed = std::max(needed, double(quota[c]) * double(probe.size()) / double(yield[c]));
    }
    const double share = needed > 0.0 ? std::min(0.5 * double(maxPaths), kRareClassPaths * needed) : 0.5 * double(maxPaths);
    for (int c = 0; c < kPhotonClassCount; ++c) {
        if (open[c] && !fillable[c]) {
            const int64_t keep = int64_t(double(yield[c]) * share / double(probe.size()));
            spare += quota[c] - keep;
            quota[c] = keep;
            open[c] = keep > 0;
        }
    }
    float others = 0.f;
    for (int c = 0; c < kPhotonClassCount; ++c) others += fillable[c] ? st.split[c] : 0.f;
    int64_t given = 0, last = -1;
    for (int c = 0; c < kPhotonClassCount && others > 0.f; ++c) {
        if (!fillable[c]) continue;
        int64_t share = int64_t(std::floor(double(spare) * st.split[c] / others));
        quota[c] += share;
        given += share;
        last = c;
    }
    if (last >= 0) quota[last] += spare - given;
}

}  // namespace

void PhotonMap::report(Stats& stats) const {
    for (int c = 0; c < kPhotonClassCount; ++c)
        stats.setCount(std::string("photons_") + photonClassName(c), double(count[c]));
    stats.setCount("photon_paths", double(pathsTraced));
}

PhotonMap tracePhotons(const Scene& scene, const RayAccel& accel, const LightSampler& lights, const PhotonSettings& st,
                       ThreadPool& pool, Reporter& reporter) {
    PhotonMap map;
    if (lights.empty() || st.photons <= 0) return map;
    // Each pass its own scrambling of the sequence, indexed by the path within the pass: the
    // radical inverse runs over an index's own digits (about 17 in base 2 for a pass's paths, 41
    // for pass · 2^40 + path), and under a point light it is a tenth of the render's profile.
    // A pass's photon rounds after its first (bits 32–39 of firstPath) scramble it anew.
    const uint64_t round = (st.firstPath >> PhotonSettings::kPathsPerRoundBits) & 0xff;
    ScrambledHalton qmc(hashKey(st.seed, Stage::Photon, st.firstPath >> PhotonSettings::kPathsPerPassBits, 0x9a55 ^ (round << 20)),
                        5 + kDimsPerBounce * st.maxDepth);

    // Quotas.
    int64_t quota[kPhotonClassCount];
    float splitSum = st.split[0] + st.split[1] + st.split[2];
    if (!(splitSum > 0.f)) throw Error(ErrorKind::Config, "the photon split must have a positive part");
    int64_t assigned = 0;
    for (int c = 0; c < kPhotonClassCount; ++c) {
        quota[c] = int64_t(std::floor(double(st.photons) * st.split[c] / splitSum));
        assigned += quota[c];
    }
    quota[kPhotonIndirect] += st.photons - assigned;
    bool open[kPhotonClassCount];
    for (int c = 0; c < kPhotonClassCount; ++c) open[c] = quota[c] > 0;
    const int64_t maxPaths = std::min<int64_t>(st.maxPaths > 0 ? st.maxPaths : 50 * st.photons, int64_t(UINT32_MAX) - kProbePaths);

    reporter.begin("photon tracing", st.photons, "photons");
    std::vector<std::vector<PhotonRay>> perPath;
    int64_t paths = 0;
    bool probed = false;
    while ((open[0] || open[1] || open[2]) && paths < maxPaths) {
        // Trace one block in parallel. The first block is a larger probe whose yield decides
        // the final quotas before anything is merged.
        int64_t block = probed ? kBlockPaths : kProbePaths;
        perPath.resize(size_t(block));
        pool.parallelFor(block, 256, [&](int64_t b, int64_t e, int) {
            for (int64_t i = b; i < e; ++i) {
                perPath[i].clear();
                tracePath(scene, accel, lights, qmc, st, st.firstPath + uint64_t(paths + i), open, perPath[i]);
            }
        });
        if (!probed) {
            rebalanceQuotas(perPath, maxPaths, st, quota, open);
            probed = true;
        }
        // Merge in path order against the quotas.
        int64_t before = int64_t(map.rays.size());
        for (int64_t i = 0; i < block; ++i) {
            for (const PhotonRay& r : perPath[i]) {
                if (!open[r.cls]) continue;
                map.rays.push_back(r);
                if (++map.count[r.cls] == quota[r.cls]) {
                    open[r.cls] = false;
                    map.pathsFor[r.cls] = paths + i + 1;
                }
            }
        }
        paths += block;
        reporter.advance(int64_t(map.rays.size()) - before);
    }
    reporter.end();
    map.pathsTraced = paths;
    // Classes still open at the path limit are normalised by every path traced.
    for (int c = 0; c < kPhotonClassCount; ++c)
        if (map.pathsFor[c] == 0 && map.count[c] > 0) map.pathsFor[c] = paths;

    // Normalise the flux and set the radius of every photon ray.
    for (PhotonRay& r : map.rays) {
        double n = double(map.pathsFor[r.cls]);
        r.flux = Vec3(DVec3(r.flux) / n);
        float h = std::sqrt(st.k[r.cls] / (kPi * float(n * st.rounds) * std::max(r.density, 1e-30f)));
        r.radius = std::clamp(h, st.minRadius[r.cls] * st.voxelSize, st.maxRadius[r.cls] * st.voxelSize) * st.radiusScale *
                   st.classScale[r.cls];
        if (st.reachToBounds) reachBounds(scene, r);
    }
    return map;
}

PhotonMap scaledKernels(const Scene& scene, const PhotonMap& photons, int cls, float factor, const PhotonSettings& st) {
    PhotonMap out;
    out.pathsFor[cls] = photons.pathsFor[cls];
    out.pathsTraced = photons.pathsTraced;
    for (const PhotonRay& r : photons.rays) {
        if (r.cls != cls) continue;
        PhotonRay s = r;
        s.radius *= factor;
        // The reach past x(i), tan θ radii, does not depend on the radius; to the bounds it is
        // counted again in the new radii (with factor < 1, more of them than before).
        if (st.reachToBounds) reachBounds(scene, s);
        out.rays.push_back(s);
        out.count[cls]++;
    }
    return out;
}

}  // namespace rs
