// The pipeline, in order (docs/design.md §1):
//   scene → Embree BVH + light sampler
//   splat methods: occlusion grid (voxelizer or cache), then passes of
//                  (eye pass [+ direct light by sampling] → occlusion tree → photon tracing
//                  → splatting) → film, the passes averaged
//   path:          passes of path tracing → film
// Stages take their inputs as const& and return their outputs by value; only this file
// knows the order. Every stage's wall time and counts go to Stats (--stats-json, EXR header).
#include "render.h"

#include <cstdio>

#include "core/error.h"
#include "scene/accel.h"
#include "splat/coverage.h"
#include "splat/eye.h"
#include "splat/irradiance.h"
#include "splat/kernel_scale.h"
#include "grid/grid_stage.h"
#include "occlusion/kdtree.h"
#include "scene/lights.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "core/stop.h"
#include "memory.h"
#include "ranks.h"
#include "path/path.h"
#include "splat/photons.h"
#include "splat/splat.h"

#ifndef RAYSPLAT_VERSION
#define RAYSPLAT_VERSION "dev"
#endif

namespace rs {

const char* versionString() { return RAYSPLAT_VERSION; }

Ranks& singleProcess() {
    static Ranks one;
    return one;
}

namespace {

// What every stage of a render is handed: the scene and what was built from it, the image
// size, the settings, and where work, progress and figures go.
struct RenderContext {
    const Scene& scene;
    const RayAccel& accel;
    const LightSampler& lights;
    const Camera& camera;
    int width, height;
    const RenderConfig& cfg;
    ThreadPool& pool;
    Reporter& reporter;
    Stats& stats;
    Ranks& ranks;
};

// Every rank's figures agree, or this throws: another rank failed and says why.
bool agreeOrStop(Ranks& ranks, bool more) {
    const Ranks::Agreement a = ranks.agree(true, more);
    if (a.failedRank >= 0)
        throw Error(ErrorKind::OtherRank, "rank " + std::to_string(a.failedRank) + " failed");
    return a.more;
}

// -- The stages' settings, from the RenderConfig (here only) ----------------------------------

EyePassSettings eyePassSettings(const RenderContext& c) {
    EyePassSettings es;
    es.width = c.width;
    es.height = c.height;
    es.spp = c.cfg.samplesPerPixel();
    es.maxSpecularDepth = c.cfg.maxDepth;
    es.directSamples = c.cfg.directBySampling() ? c.cfg.lightSamples : 0;
    es.directSpp = c.cfg.directBySampling() ? c.cfg.directSpp : 0;
    es.seed = c.cfg.seed;
    return es;
}

PhotonSettings photonSettings(const RenderConfig& cfg, float voxelSize) {
    PhotonSettings ps;
    ps.photons = cfg.photons;
    ps.split = cfg.photonSplit();
    ps.k = cfg.kernelPhotons;
    ps.minRadius = cfg.minRadius;
    ps.maxRadius = cfg.maxRadius;
    ps.voxelSize = voxelSize;
    ps.maxDepth = cfg.maxDepth;
    ps.seed = cfg.seed;
    ps.reachToBounds = cfg.visibilityByRays();
    return ps;
}

CoverageSettings coverageSettings(const RenderConfig& cfg) {
    CoverageSettings cs;
    cs.probes = cfg.coverageProbes;
    cs.minCoverage = cfg.minCoverage;
    cs.seed = cfg.seed;
    return cs;
}

PathSettings pathSettings(const RenderContext& c) {
    PathSettings ps;
    ps.width = c.width;
    ps.height = c.height;
    ps.spp = c.cfg.samplesPerPixel();
    ps.maxDepth = c.cfg.maxDepth;
    ps.seed = c.cfg.seed;
    return ps;
}

SplatSettings splatSettings(const RenderConfig& cfg) {
    SplatSettings splat;
    splat.visibility = cfg.method == Method::Splat;
    splat.receiverWindow = cfg.visibilityByRays();
    return splat;
}

// -- Passes -------------------------------------------------------------------------------------

// What one rank renders of one pass: share `share` of `shares` equal parts of its photons
// (splat) or rows (path); the eye pass's own light (emission, sampled direct light, albedo,
// normal) comes from share 0 alone.
struct PassShare {
    int pass = 0;
    int share = 0, shares = 1;
};

// Progressive rendering: cfg.passCount() passes, or with a time limit as many as fit (at least
// one), averaged with equal weights, summed in fixed point. With several ranks
// (docs/design.md §11) passes go round by round, one pass a rank, pass p to rank p mod N; with
// fewer passes than ranks every rank renders a share of every pass. After each round the
// ranks agree: on errors, and (rank 0's clock) on whether another round fits the time limit.
// With firstShared the first pass is rendered by every rank, a share each, before any other:
// what it measures decides the passes after it (the kernel scale), and it may say how long
// they will take (nextSeconds > 0, at rank 0).
template <class RenderPass>
Film renderPasses(const RenderContext& c, RenderPass&& pass, bool firstShared = false, const double* nextSeconds = nullptr) {
    Timer t;
    FixedFilm sum(c.width, c.height);
    const bool timed = c.cfg.timeLimit > 0.0;
    const int wanted = c.cfg.passCount();
    const int ranks = c.ranks.size(), me = c.ranks.rank();
    const bool shared = !timed && wanted < ranks;
    const bool several = timed || wanted > 1;
    if (several) c.reporter.begin("rendering", timed ? 0 : wanted, "passes");
    int passes = 0;
    double longest = 0.0;
    for (bool more = true; more;) {
        throwIfStopped();
        const bool together = shared || (firstShared && passes == 0 && ranks > 1);
        const int round = together ? 1 : timed ? ranks : std::min(ranks, wanted - passes);
        Timer one;
        if (together)
            pass(PassShare{passes, me, ranks}, sum);
        else if (me < round)
            pass(PassShare{passes + me, 0, 1}, sum);
        // The first round's time counts until a second one is timed: it measured for the others.
        longest = passes == 0 || (firstShared && passes == 1) ? one.seconds() : std::max(longest, one.seconds());
        if (firstShared && passes == 0 && nextSeconds && *nextSeconds > 0.0) longest = *nextSeconds;
        passes += round;
        if (several) c.reporter.advance(round);
        // Under a time limit, also no further than the passes whose sample indices fit (maxPasses).
        more = agreeOrStop(c.ranks, timed ? t.seconds() + longest <= c.cfg.timeLimit && passes + ranks <= c.cfg.maxPasses()
                                          : passes < wanted);
    }
    if (several) c.reporter.end();
    for (std::vector<int64_t>& buffer : sum.buffers) c.ranks.sumAtRoot(buffer);
    c.stats.setCount("passes", passes);
    // The image is rank 0's; the others have nothing left to do that could fail.
    return me == 0 ? sum.average(passes) : Film();
}

Film renderPath(const RenderContext& c) {
    PathSettings ps = pathSettings(c);
    const int spp = ps.spp;
    int passes = 0;
    Timer t;
    Film film = renderPasses(c, [&](const PassShare& share, FixedFilm& sum) {
        passes = std::max(passes, share.pass + 1);
        ps.firstSample = share.pass * spp;
        ps.rowBegin = c.height * share.share / share.shares;
        ps.rowEnd = c.height * (share.share + 1) / share.shares;
        sum.add(renderPathPass(c.scene, c.accel, c.lights, c.camera, ps, c.pool, c.reporter));
    });
    c.stats.addTime("render", t.seconds());
    c.stats.setCount("samples_per_pixel", double(passes) * spp);
    c.stats.setCount("paths_per_second", double(c.width) * c.height * passes * spp / std::max(t.seconds(), 1e-9));
    return film;
}

// Figures summed over a render's passes (the last pass's sizes are reported as they come).
struct SplatTotals {
    SplatStats splat;
    CoverageStats coverage;
    int64_t photonsStored = 0;
    double photonMb = 0.0;
};

// The photon ray --photon asks for, as traced (before its coverage); an error when the pass
// has fewer.
PhotonRay replayedRay(const RenderContext& c, const PhotonMap& photons) {
    if (c.cfg.replayIndex >= int64_t(photons.rays.size()))
        throw Error(ErrorKind::Config, "`photon` " + std::to_string(c.cfg.replayPass) + ":" + std::to_string(c.cfg.replayIndex) +
                                           ": pass " + std::to_string(c.cfg.replayPass) + " has " +
                                           std::to_string(photons.rays.size()) + " photon rays");
    return photons.rays[size_t(c.cfg.replayIndex)];
}

// One line: the replayed ray's class, ends, flux, kernel and the coverage its flux was divided by.
void reportReplayed(const RenderContext& c, const PhotonRay& traced, const PhotonRay& ray, float voxel) {
    const Vec3 hit = ray.origin + ray.length * ray.dir;
    const float divided = luminance(ray.flux) > 0.f ? luminance(traced.flux) / luminance(ray.flux) : 0.f;
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "photon ray %lld of pass %d: %s, from (%.4g, %.4g, %.4g) to (%.4g, %.4g, %.4g), flux (%.4g, %.4g, %.4g) W, "
                  "radius %.4g m (%.3g voxels), reach %.3g radii, flux divided by coverage %.3g",
                  (long long)c.cfg.replayIndex, c.cfg.replayPass, photonClassName(ray.cls), ray.origin.x, ray.origin.y,
                  ray.origin.z, hit.x, hit.y, hit.z, ray.flux.x, ray.flux.y, ray.flux.z, ray.radius,
                  ray.radius / voxel, ray.reach, divided);
    c.reporter.info(buf);
}

// What a pass's photons land on (docs/design.md §8): every eye sample, through the occlusion tree
// over them, for direct and caustic photons; with sparse receivers (irradiance.h) the indirect
// photons on the receivers, through a tree of their own, gathered back to the eye samples. In a
// pass shared by the ranks the receivers' light is summed at rank 0 before the gather, so the
// image is a single process's to the bit.
class PassTargets {
public:
    // `samples` in pixel order, as the eye pass gives them; spacing 0: no sparse receivers.
    PassTargets(const RenderContext& c, const OcclusionGrid& grid, EyeSamples& samples, float spacing,
                OcclusionTreeStats* treeStats)
        : c_(c), samples_(samples) {
        if (spacing > 0.f) {
            receivers_ = chooseReceivers(samples, c.width, c.height, spacing, c.pool);
            receiverTree_ = buildOcclusionTree(grid, receivers_.samples, c.pool);
            sparse_ = true;
        }
        tree_ = buildOcclusionTree(grid, samples, c.pool, treeStats);
    }

    const OcclusionTree& tree() const { return tree_; }
    size_t receivers() const { return sparse_ ? receivers_.slots() : samples_.size(); }

    // Adds `photons`' light (this rank's share, settings.share of settings.shares) to `part`.
    void splat(const PhotonMap& photons, const SplatSettings& settings, FixedFilm& part, SplatTotals* totals) const {
        SplatStats* stats = totals ? &totals->splat : nullptr;
        CoverageStats* coverage = totals ? &totals->coverage : nullptr;
        if (!sparse_) {
            splatPhotons(c_.accel, tree_, samples_, photons, settings, part, c_.pool, c_.reporter, stats, coverage);
            return;
        }
        PhotonMap indirect = photons, others = photons;
        indirect.rays.clear(), others.rays.clear();
        for (const PhotonRay& r : photons.rays) (r.cls == kPhotonIndirect ? indirect : others).rays.push_back(r);
        if (!others.rays.empty())
            splatPhotons(c_.accel, tree_, samples_, others, settings, part, c_.pool, c_.reporter, stats, coverage);
        if (indirect.rays.empty()) return;
        FixedFilm slots;
        slots.width = int(receivers_.slots()), slots.height = 1;
        slots.buffers[kIndirect].assign(receivers_.slots() * 3, 0);
        SplatSettings sparse = settings;
        sparse.visibilityPlanes = false;  // a few rays a photon: finding the triangles near it cost more than they spared
        splatPhotons(c_.accel, receiverTree_, receivers_.samples, indirect, sparse, slots, c_.pool, c_.reporter, stats, coverage);
        if (settings.shares > 1) c_.ranks.sumAtRoot(slots.buffers[kIndirect]);
        if (settings.share == 0)
            gatherIrradiance(receivers_, samples_, slots.buffers[kIndirect], FixedFilm::kScale, part.buffers[kIndirect], c_.pool);
    }

private:
    const RenderContext& c_;
    EyeSamples& samples_;
    OcclusionTree tree_;
    bool sparse_ = false;
    IrradianceReceivers receivers_;
    OcclusionTree receiverTree_;
};

// The scale at which the first pass keeps its probed quarter's light, for the scale m chosen.
float keptProbeScale(float m) { return m < std::sqrt(0.5f) ? 0.5f : 1.f; }

// The first pass's probe of the indirect kernels' scale (splat/kernel_scale.h): a quarter of
// its indirect photons splatted in halves at scales 1 and ½. Each rank splats its share of
// each; the halves are summed at rank 0, which chooses the scale m and tells the others. The
// pass's own indirect light is then the quarter's, at whichever of 1 and ½ is nearer m, and the
// other three quarters' at m.
class KernelScaleProbeStep {
public:
    KernelScaleProbeStep(const RenderContext& c, const PassTargets& targets, const EyePass& eye, const SplatSettings& splat)
        : c_(c), targets_(targets), eye_(eye), splat_(splat), values_(size_t(c.width) * c.height * 3) {}

    // `indirect`: the pass's indirect photons before their coverage; `other`: seconds of the
    // pass apart from their splat; `whole`: runs since the passes began. Adds their light to
    // `sum` and returns the scale chosen.
    float run(const PhotonMap& indirect, const PhotonSettings& ps, FixedFilm& sum, SplatTotals& totals, const Timer& whole,
              double other) {
        const size_t quarter = indirect.rays.size() / KernelScaleProbe::kShare;
        std::vector<int64_t> halves(4 * values_);  // A, B, C, D: the indirect layer of each
        std::vector<int64_t> mine[2];              // this rank's light of the quarter at 1 and at ½
        FixedFilm part;  // the splat's layers only
        part.width = c_.width, part.height = c_.height;
        for (int l = 0; l < kProbeLayers; ++l) part.buffers[l].assign(values_, 0);
        double seconds[2];  // the quarter's splat at 1 and at ½
        for (int f = 0; f < 2; ++f) {
            Timer t;
            const PhotonMap scaled = scaledKernels(c_.scene, slice(indirect, 0, quarter), kPhotonIndirect, f ? 0.5f : 1.f, ps);
            mine[f].assign(values_, 0);
            for (int h = 0; h < 2; ++h) {
                splatInto(slice(scaled, h ? quarter / 2 : 0, h ? scaled.rays.size() : quarter / 2), part, f ? nullptr : &totals);
                std::copy(part.buffers[kIndirect].begin(), part.buffers[kIndirect].end(), halves.begin() + (2 * f + h) * values_);
                for (size_t i = 0; i < values_; ++i) mine[f][i] += part.buffers[kIndirect][i];
            }
            seconds[f] = t.seconds();
        }
        c_.ranks.sumAtRoot(halves);

        double scale = 1.0;
        if (c_.ranks.rank() == 0) {
            std::vector<float> light(values_);
            for (size_t i = 0; i < values_; ++i) {
                const int ch = int(i % 3);
                light[i] = eye_.film.layers[kEmission][i / 3][ch] + eye_.film.layers[kDirect][i / 3][ch] +
                           float(double(halves[i] + halves[values_ + i]) * KernelScaleProbe::kShare / FixedFilm::kScale);
            }
            const KernelScaleProbe probe = probeKernelScale(&halves[0], &halves[values_], &halves[2 * values_],
                                                            &halves[3 * values_], light, FixedFilm::kScale);
            KernelScalePlan plan;
            plan.passes = c_.cfg.renderPassCount();
            plan.alpha = c_.cfg.alpha;
            if (c_.cfg.timeLimit > 0.0) {  // the user asked for time: the passes are counted by it
                plan.timed = true;
                plan.secondsLeft = c_.cfg.timeLimit - whole.seconds();
                plan.passOther = other;
                // a + b·h² for the quarter, from its two splats (b: the part that grows with the
                // kernel's area), then for all the indirect photons.
                const double b = std::max(0.0, seconds[0] - seconds[1]) * 4.0 / 3.0, a = std::max(0.0, seconds[0] - b);
                plan.splatFixed = a * KernelScaleProbe::kShare;
                plan.splatScaled = b * KernelScaleProbe::kShare;
                plan.passesPerRound = c_.ranks.size();
            }
            scale = chooseKernelScale(probe, plan);
            if (plan.timed) nextSeconds_ = passSeconds(plan, float(scale));
            const double least = expectedKernelError(probe, plan, float(scale));
            c_.stats.setCount("kernel_probe_gain", least > 0.0 ? expectedKernelError(probe, plan, 1.f) / least : 1.0);
            c_.stats.setCount("kernel_probe_noise", probe.noise);
            c_.stats.setCount("kernel_probe_finer_noise", probe.finerNoise);
            c_.stats.setCount("kernel_probe_bias", probe.bias());
        }
        c_.ranks.broadcast(&scale, 1);
        const float m = float(scale);
        std::vector<int64_t>& light = sum.buffers[kIndirect];
        const std::vector<int64_t>& kept = mine[keptProbeScale(m) < 1.f ? 1 : 0];
        for (size_t i = 0; i < values_; ++i) FixedFilm::addSaturating(light[i], kept[i]);
        splatInto(scaledKernels(c_.scene, slice(indirect, quarter, indirect.rays.size()), kPhotonIndirect, m, ps), part, &totals);
        sum.add(part);
        return m;
    }
    // With a time limit, at rank 0: the seconds a later pass is expected to take.
    double nextSeconds() const { return nextSeconds_; }

    // Ray `index` of the first pass's photons (path order, before coverage) as that pass
    // splatted it under the probe, the scale m chosen: in its part (the other classes, the
    // probed quarter of the indirect ones or the rest), at that part's scale.
    static PhotonRay asSplatted(const RenderContext& c, const PhotonMap& traced, size_t index, float m,
                                const PhotonSettings& ps) {
        PhotonMap part = traced;
        part.rays.clear();
        const bool indirect = traced.rays[index].cls == kPhotonIndirect;
        size_t at = 0;
        for (size_t i = 0; i < traced.rays.size(); ++i) {
            if ((traced.rays[i].cls == kPhotonIndirect) != indirect) continue;
            if (i == index) at = part.rays.size();
            part.rays.push_back(traced.rays[i]);
        }
        if (indirect) {
            const size_t quarter = part.rays.size() / KernelScaleProbe::kShare;
            const bool probed = at < quarter;
            part = scaledKernels(c.scene, probed ? slice(part, 0, quarter) : slice(part, quarter, part.rays.size()),
                                 kPhotonIndirect, probed ? keptProbeScale(m) : m, ps);
            at -= probed ? 0 : quarter;
        }
        return part.rays[at];
    }

private:
    static constexpr int kProbeLayers = kCaustic + 1;  // the layers a splat writes: direct, indirect, caustic

    // Photons [first, last) of `photons`, in path order.
    static PhotonMap slice(const PhotonMap& photons, size_t first, size_t last) {
        PhotonMap out = photons;
        out.rays.assign(photons.rays.begin() + first, photons.rays.begin() + last);
        return out;
    }
    void splatInto(const PhotonMap& photons, FixedFilm& part, SplatTotals* totals) const {
        for (std::vector<int64_t>& b : part.buffers) std::fill(b.begin(), b.end(), 0);
        targets_.splat(photons, splat_, part, totals);
    }

    const RenderContext& c_;
    const PassTargets& targets_;
    const EyePass& eye_;
    const SplatSettings& splat_;
    const size_t values_;
    double nextSeconds_ = 0.0;
};

Film renderSplat(const RenderContext& c, StagedFiles* outputs) {
    Stats& stats = c.stats;
    // The occlusion grid, once (docs/design.md §5–6), where the mask needs it or its file was asked
    // for. Otherwise the tree indexes the eye samples over an empty grid of the same geometry:
    // nothing occludes in it, and the receiver rules alone decide (--visibility rays), or nothing
    // does (splat-novis).
    const bool mask = c.cfg.needsMask();
    OcclusionGrid grid = mask || !c.cfg.vdb.empty() || !c.cfg.cacheDir.empty()
                             ? buildGrid(c.scene, c.cfg.gridSettings(), c.pool, c.reporter, stats, outputs)
                             : OcclusionGrid(gridForBounds(c.scene.bounds, c.cfg.grid));
    if (!mask) grid = OcclusionGrid(grid.geometry);
    EyePassSettings es = eyePassSettings(c);
    PhotonSettings ps = photonSettings(c.cfg, grid.geometry.voxelSize);
    CoverageSettings cs = coverageSettings(c.cfg);
    const bool coverage = c.cfg.visibilityByRays() && cs.probes > 0;
    const bool sparse = c.cfg.sparseReceivers();
    SplatSettings splat = splatSettings(c.cfg);
    SplatTotals totals;
    // The indirect kernels' scale: given, or measured by the first pass (kernel_scale.h).
    const bool probing = c.cfg.probesKernelScale();
    double nextPass = 0.0;  // the probe's estimate of a later pass's seconds
    ps.classScale[kPhotonIndirect] = probing ? 1.f : c.cfg.kernelScaleOrOne();
    Timer whole;

    // Every pass: new eye samples (the next S of each pixel's sequence), the tree over them,
    // new photons (a fresh range of paths) with shrunk kernels, splatted (docs/design.md §4, §7–9).
    // A replay renders its pass alone, after the first pass's probe where the scale needs it.
    auto renderPass = [&](int pass, const PassShare& share, FixedFilm& sum, bool replay) {
        Timer t;
        es.firstSample = pass * es.spp;
        es.firstDirectSample = pass * es.directSpp;
        EyePass eye = traceEyePass(c.scene, c.accel, &c.lights, c.camera, es, c.pool, c.reporter);
        stats.addTime("eye", t.seconds());
        stats.setCount("eye_samples", double(eye.samples.size()));
        stats.setCount("eye_samples_mb", double(eye.samples.bytes()) / kMB);

        t = Timer();
        OcclusionTreeStats ts;
        const float spacing = sparse ? c.cfg.receiverSpacing * ps.minRadius[kPhotonIndirect] * grid.geometry.voxelSize *
                                           passRadiusScale(pass, c.cfg.alpha) *
                                           (probing && pass == 0 ? 0.5f : ps.classScale[kPhotonIndirect])
                                     : 0.f;
        const PassTargets targets(c, grid, eye.samples, spacing, &ts);
        stats.addTime("tree", t.seconds());
        stats.setCount("receivers", double(targets.receivers()));
        ts.report(stats);
        if (pass == 0 && ts.samplesOutside > 0)
            c.reporter.warn(c.scene.path + ": " + std::to_string(ts.samplesOutside) +
                            " eye samples lie outside the grid and get no light");

        t = Timer();
        ps.firstPath = uint64_t(pass) << PhotonSettings::kPathsPerPassBits;
        ps.radiusScale = passRadiusScale(pass, c.cfg.alpha);
        PhotonSettings passPs = ps;  // the probe's pass traces at scale 1 and scales its parts itself
        if (probing && pass == 0) passPs.classScale[kPhotonIndirect] = 1.f;
        PhotonMap photons = tracePhotons(c.scene, c.accel, c.lights, passPs, c.pool, c.reporter);
        const PhotonMap probeTraced = replay && probing && pass == 0 ? photons : PhotonMap();
        stats.addTime("photons", t.seconds());
        // The probe's pass splats its indirect photons apart, at the scales it measures.
        const bool probe = probing && pass == 0 && !replay;
        PhotonMap indirect;
        if (probe) {
            auto begin = std::stable_partition(photons.rays.begin(), photons.rays.end(),
                                               [](const PhotonRay& r) { return r.cls != kPhotonIndirect; });
            indirect.rays.assign(begin, photons.rays.end());
            photons.rays.erase(begin, photons.rays.end());
        }
        const PhotonRay traced = replay ? replayedRay(c, photons) : PhotonRay{};
        // The kernels' coverage is measured by the splat, as the receiver rules will see it, for
        // the photons that reach an eye sample (docs/design.md §8).
        cs.pass = uint64_t(pass);
        splat.coverage = coverage ? &cs : nullptr;
        photons.report(stats);
        totals.photonsStored += int64_t(photons.rays.size() + indirect.rays.size());
        totals.photonMb = std::max(totals.photonMb, double(photons.bytes()) / kMB);

        if (replay) {  // that ray alone, and no light of the eye pass's
            const PhotonRay ray = probeTraced.rays.empty()
                                      ? photons.rays[size_t(c.cfg.replayIndex)]
                                      : KernelScaleProbeStep::asSplatted(c, probeTraced, size_t(c.cfg.replayIndex),
                                                                         ps.classScale[kPhotonIndirect], passPs);
            photons.rays.assign(1, ray);
            PhotonRay covered = ray;  // as the splat will cover it
            CoverageStats unused;
            if (coverage) normalizeCoverage(c.accel, covered, cs, unused);
            reportReplayed(c, traced, covered, grid.geometry.voxelSize);
        }
        // The eye pass's own light (emission, albedo, normal, sampled direct light), then the
        // photons' (this rank's share of them).
        t = Timer();
        if (share.share == 0 && !replay) sum.add(eye.film);
        splat.share = share.share;
        splat.shares = share.shares;
        targets.splat(photons, splat, sum, &totals);
        const double other = whole.seconds();
        if (probe) {
            cs.pass = uint64_t(pass);
            KernelScaleProbeStep step(c, targets, eye, splat);
            const float m = step.run(indirect, passPs, sum, totals, whole, other);
            nextPass = step.nextSeconds();
            ps.classScale[kPhotonIndirect] = m;
            char line[160];
            std::snprintf(line, sizeof line, "indirect kernels at scale %.3g, from the bias and noise the first pass measured", m);
            c.reporter.info(line);
        }
        stats.addTime("splat", t.seconds());
        stats.setCount("photon_mb", totals.photonMb);
        stats.setCount("photons_stored", double(totals.photonsStored));
        stats.setCount("radius_scale", ps.radiusScale);
        stats.setCount("kernel_scale", ps.classScale[kPhotonIndirect]);
        totals.splat.report(stats);
        if (coverage) totals.coverage.report(stats);
    };
    const bool replay = c.cfg.replays();
    if (replay && probing) {  // the scale, as the render's first pass chooses it
        FixedFilm unused(c.width, c.height);
        renderPass(0, PassShare{0, 0, 1}, unused, false);
        totals = SplatTotals();
    }
    Film film = renderPasses(
        c, [&](const PassShare& share, FixedFilm& sum) { renderPass(replay ? c.cfg.replayPass : share.pass, share, sum, replay); },
        probing, &nextPass);
    if (replay)
        c.reporter.info("photon ray " + std::to_string(c.cfg.replayIndex) + " reached " +
                        std::to_string(int64_t(stats.count("splat_contributions"))) + " eye samples");
    return film;
}

}  // namespace

RenderResult render(const Scene& scene, const RenderConfig& cfg, Reporter& reporter, Ranks& ranks) {
    cfg.validate();
    RenderResult result;
    Stats& stats = result.stats;
    Camera camera = scene.camera(cfg.camera);
    int width, height;
    cfg.resolution(camera.aspect, width, height);
    // Refuse settings the machine cannot hold before allocating anything large.
    const GridGeometry geometry = cfg.splats() || !cfg.vdb.empty() || !cfg.cacheDir.empty()
                                      ? gridForBounds(scene.bounds, cfg.grid)
                                      : GridGeometry();
    const int gridDims[3] = {geometry.dims.x, geometry.dims.y, geometry.dims.z};
    const int threads = cfg.threads > 0 ? cfg.threads : ThreadPool::hardwareThreads();
    const MemoryEstimate memory = estimateMemory(cfg, gridDims, scene.triangleCount(), width, height, threads);
    checkMemory(memory, cfg.maxMemory, ranks.sizeOnThisMachine());
    stats.setCount("memory_estimate_mb", memory.total() / kMB);
    agreeOrStop(ranks, false);  // every rank got this far: the scene loaded and fits

    ThreadPool pool(cfg.threads);
    stats.setCount("threads", pool.size());
    stats.setCount("ranks", ranks.size());
    stats.setCount("simd_lanes", int(traversalIsa()));  // the occlusion tree traversal's: 4 (sse2) or 16 (avx512)
    stats.setCount("triangles", double(scene.triangleCount()));
    stats.setCount("width", width);
    stats.setCount("height", height);

    // Ray-tracing acceleration structure and the lights.
    Timer t;
    RayAccel accel(scene, pool.size());
    const Environment environment = cfg.environment(scene);
    LightSampler lights(scene, &environment);
    stats.addTime("bvh", t.seconds());
    if (lights.empty()) reporter.warn(scene.path + ": the scene has no lights and no environment: the image will be black");

    const RenderContext context{scene, accel, lights, camera, width, height, cfg, pool, reporter, stats, ranks};
    if (cfg.splats()) {
        result.film = renderSplat(context, result.outputs.get());
    } else {
        // The path tracer does not need the grid; it is built only when asked for.
        if (!cfg.vdb.empty() || !cfg.cacheDir.empty()) buildGrid(scene, cfg.gridSettings(), pool, reporter, stats, result.outputs.get());
        result.film = renderPath(context);
    }

    result.attributes = cfg.attributes();
    result.attributes["scene"] = scene.path;
    result.attributes["version"] = versionString();
    result.attributes["simd"] = isaName(traversalIsa());
    if (cfg.splats() && cfg.probesKernelScale() && !cfg.replays())
        result.attributes["kernelScale"] = "auto: " + std::to_string(stats.count("kernel_scale"));
    if (!cfg.splats()) result.attributes["spp"] = std::to_string(int64_t(stats.count("samples_per_pixel")));
    for (const auto& [stage, s] : stats.seconds) {
        char b[32];
        std::snprintf(b, sizeof b, "%.4f", s);
        result.attributes["time." + stage] = b;
    }
    return result;
}

void writeOutputs(RenderResult& result, const RenderConfig& cfg) {
    // All or nothing: every file is written under a temporary name first.
    StagedFiles& out = *result.outputs;
    throwIfStopped();
    writeExrTo(out.stage(cfg.output), cfg.output, result.film, result.attributes,
               cfg.threads > 0 ? cfg.threads : ThreadPool::hardwareThreads(), cfg.blenderLayer);
    if (!cfg.png.empty()) writeFileTo(out.stage(cfg.png), cfg.png, encodePng(result.film, cfg.exposure));
    if (!cfg.statsJson.empty()) writeFileTo(out.stage(cfg.statsJson), cfg.statsJson, result.stats.json());
    throwIfStopped();  // the last moment a stop leaves nothing: the renames follow
    out.commit();
}

}  // namespace rs
