// One pass of photon ray splatting, in order (splat_pass.h): eye pass → receivers and trees →
// photons → splat (the first pass: with the kernel scale's probe). Every stage's settings are
// built here from the RenderConfig, once.
#include "splat_pass.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "grid/grid_stage.h"
#include "kernel_probe.h"
#include "occlusion/kdtree.h"
#include "scene/accel.h"
#include "scene/lights.h"
#include "scene/scene.h"
#include "splat/kernel_scale.h"
#include "splat/targets.h"

namespace rs {

namespace {

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
    ps.classScale[kPhotonIndirect] = cfg.probesKernelScale() ? 1.f : cfg.kernelScaleOrOne();
    return ps;
}

CoverageSettings coverageSettings(const RenderConfig& cfg) {
    CoverageSettings cs;
    cs.probes = cfg.coverageProbes;
    cs.minCoverage = cfg.minCoverage;
    cs.atSamples = cfg.coverageAtSamples;
    cs.seed = cfg.seed;
    return cs;
}

SplatSettings splatSettings(const RenderConfig& cfg) {
    SplatSettings splat;
    splat.minCoverage = cfg.minCoverage;
    splat.visibility = cfg.method == Method::Splat;
    splat.receiverWindow = cfg.visibilityByRays();
    return splat;
}

// The share of each photon class's light that a splat of the pass's paths [0, covered) gives.
void classShares(const PhotonMap& photons, uint64_t coveredOthers, uint64_t coveredIndirect, double share[3]) {
    for (int c = 0; c < kPhotonClassCount; ++c) {
        const uint64_t covered = c == kPhotonIndirect ? coveredIndirect : coveredOthers;
        const int64_t paths = photons.pathsFor[c];
        share[c] = paths <= 0 || covered >= uint64_t(paths) ? 1.0 : double(covered) / double(paths);
    }
}

// The photon ray --photon asks for, as traced (before its coverage); an error when the pass
// has fewer.
PhotonRay replayedRay(const RenderContext& c, const PhotonMap& photons) {
    if (c.cfg.replayIndex >= int64_t(photons.rays.size()))
        throw Error(ErrorKind::Config, "`photon` " + std::to_string(c.cfg.replayPass) + ":" + std::to_string(c.cfg.replayIndex) +
                                           ": pass " + std::to_string(c.cfg.replayPass) + " has " +
                                           std::to_string(photons.rays.size()) + " photon rays");
    return photons.rays[size_t(c.cfg.replayIndex)];
}

// One line: the replayed ray's class, ends, flux, kernel and the coverage its flux was divided by,
// and the lines across its kernel by which its samples divide their light (KernelEdge).
void reportReplayed(const RenderContext& c, const PhotonRay& traced, const PhotonRay& ray, float voxel, int lines) {
    const Vec3 hit = ray.origin + ray.length * ray.dir;
    const float divided = luminance(ray.flux) > 0.f ? luminance(traced.flux) / luminance(ray.flux) : 0.f;
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "photon ray %lld of pass %d: %s, from (%.4g, %.4g, %.4g) to (%.4g, %.4g, %.4g), flux (%.4g, %.4g, %.4g) W, "
                  "radius %.4g m (%.3g voxels), reach %.3g radii, flux divided by coverage %.3g, %d kernel edge%s at the samples",
                  (long long)c.cfg.replayIndex, c.cfg.replayPass, photonClassName(ray.cls), ray.origin.x, ray.origin.y,
                  ray.origin.z, hit.x, hit.y, hit.z, ray.flux.x, ray.flux.y, ray.flux.z, ray.radius,
                  ray.radius / voxel, ray.reach, divided, lines, lines == 1 ? "" : "s");
    c.reporter.info(buf);
}

// The first path of a pass's photon round: pass p's from p · 2^40, its round r's 2^32 further per r.
uint64_t firstPathOf(int pass, int round) {
    return (uint64_t(pass) << PhotonSettings::kPathsPerPassBits) + (uint64_t(round) << PhotonSettings::kPathsPerRoundBits);
}

}  // namespace

SplatPasses::SplatPasses(const RenderContext& c, StagedFiles* outputs, PhotonStore* store)
    : c_(c), store_(store), eye_(eyePassSettings(c)), coverage_(coverageSettings(c.cfg)), splat_(splatSettings(c.cfg)),
      probing_(c.cfg.probesKernelScale() && !store), sparse_(c.cfg.sparseReceivers()),
      measuresCoverage_(c.cfg.visibilityByRays() && c.cfg.coverageProbes > 0) {
    // The occlusion grid, once (docs/design.md §5–6), where the mask needs it or its file was asked
    // for. Otherwise the tree indexes the eye samples over an empty grid of the same geometry:
    // nothing occludes in it, and the receiver rules alone decide (--visibility rays), or nothing
    // does (splat-novis).
    // A walkthrough's frames share the first frame's.
    const bool mask = c.cfg.needsMask();
    c.stats.setCount("grid_reused", store && store->grid ? 1 : 0);
    if (store && store->grid) {
        grid_ = store->grid;
    } else {
        OcclusionGrid grid = mask || !c.cfg.vdb.empty() || !c.cfg.cacheDir.empty()
                                 ? buildGrid(c.scene, c.cfg.gridSettings(), c.pool, c.reporter, c.stats, outputs)
                                 : OcclusionGrid(gridForBounds(c.scene.bounds, c.cfg.grid));
        if (!mask) grid = OcclusionGrid(grid.geometry);
        grid_ = std::make_shared<const OcclusionGrid>(std::move(grid));
        if (store) store->grid = grid_;
    }
    photons_ = photonSettings(c.cfg, grid_->geometry.voxelSize);
    // The kernels' coverage is measured by the splat, as the receiver rules will see it, for the
    // photons that reach an eye sample (docs/design.md §8); stored photons have theirs already.
    splat_.coverage = measuresCoverage_ && !store ? &coverage_ : nullptr;
    c.stats.setCount("photon_passes_traced", 0);  // by this render: none where a store had them all
}

// The eye samples of pass `pass` (the next S of each pixel's sequence) and its direct film.
EyePass SplatPasses::traceEye(int pass, const Deadline& deadline) {
    Timer t;
    eye_.firstSample = pass * eye_.spp;
    eye_.firstDirectSample = pass * eye_.directSpp;
    eye_.measureFilmNoise = pass == 0 && probing_ && c_.cfg.photonRoundsAuto();
    // The first pass, which every rank renders, measures where the film's light is spread; the
    // passes after it take more film samples there (filmExtraSamples).
    eye_.measureFilmSpread = pass == 0 && probing_ && eye_.directSpp >= 2;
    eye_.extraFilm = extraFilmOf(pass);
    EyePassSettings settings = eye_;
    if (pass == 0) {
        const EyePassSize size = firstEyePass(deadline);
        settings.spp = size.spp, settings.directSpp = size.directSpp;
    }
    EyePass eye = traceEyePass(c_.scene, c_.accel, &c_.lights, c_.camera, settings, c_.pool, c_.reporter);
    // The film's noise as a film of D samples would have it (the passes' rounds weigh that).
    const float smaller = eye_.directSpp > 0 ? float(settings.directSpp) / float(eye_.directSpp) : 1.f;
    for (Vec3& v : eye.filmNoise) v *= smaller;
    if (eye_.measureFilmSpread) {
        double removed[2] = {0.0, 0.0};
        extraFilm_ = filmExtraSamples(eye.filmSpread, eye_.directSpp, removed);
        c_.stats.setCount("film_extra_variance_removed", removed[0]);
        c_.stats.setCount("film_extra_samples_share", removed[1]);
    }
    eyeSeconds_ = t.seconds();
    c_.stats.addTime("eye", eyeSeconds_);
    c_.stats.setCount("eye_samples", double(eye.samples.size()));
    c_.stats.setCount("eye_samples_mb", double(eye.samples.bytes()) / kMB);
    return eye;
}

// Under a time limit, the first pass's camera samples a pixel: S and D where its eye pass fits a
// share of the time left (by estimateEyePass), else fewer (eyePassWithin). Rank 0 chooses for
// every rank. Without a limit, S and D.
EyePassSize SplatPasses::firstEyePass(const Deadline& deadline) const {
    EyePassSize size{eye_.spp, eye_.directSpp};
    if (!deadline.clock) return size;
    double chosen[2] = {double(size.spp), double(size.directSpp)};
    if (c_.ranks.rank() == 0) {
        const EyePassCost cost = estimateEyePass(c_.scene, c_.accel, &c_.lights, c_.camera, eye_, c_.pool);
        const EyePassSize fits = eyePassWithin(cost, kFirstEyeShare * (deadline.seconds - deadline.clock->seconds()),
                                               size.spp, size.directSpp);
        chosen[0] = fits.spp, chosen[1] = fits.directSpp;
    }
    c_.ranks.broadcast(chosen, 2);
    c_.stats.setCount("first_pass_spp", chosen[0]);
    c_.stats.setCount("first_pass_direct_spp", chosen[1]);
    if (int(chosen[0]) < size.spp || int(chosen[1]) < size.directSpp)
        c_.reporter.info("the first pass at " + std::to_string(int(chosen[0])) + " eye and " + std::to_string(int(chosen[1])) +
                         " film samples a pixel, for its eye pass to fit the time limit");
    return EyePassSize{int(chosen[0]), int(chosen[1])};
}

double SplatPasses::renderFilm(int pass, FixedFilm& sum) {
    Timer t;
    EyePassSettings film = eye_;
    film.spp = 0;
    film.firstDirectSample = pass * film.directSpp;
    film.measureFilmNoise = film.measureFilmSpread = false;
    film.extraFilm = extraFilmOf(pass);
    sum.add(traceEyePass(c_.scene, c_.accel, &c_.lights, c_.camera, film, c_.pool, c_.reporter).film);
    sum.countFilmPass(film.directSamples > 0);
    c_.stats.addTime("film", t.seconds());
    return t.seconds();
}

// The indirect photons' receivers' spacing in pass `pass` (0: none): a share of the smallest
// indirect kernel the pass can splat (the first pass probes with half-wide ones), over the root
// of the pass's photon rounds: R rounds leave 1/R of one round's noise for the receivers'
// smoothing to take out, and its blur stays (docs/design.md §8).
float SplatPasses::receiverSpacing(int pass) const {
    if (!sparse_) return 0.f;
    const float scale = probing_ && pass == 0 ? 0.5f : photons_.classScale[kPhotonIndirect];
    return c_.cfg.receiverSpacing * photons_.minRadius[kPhotonIndirect] * grid_->geometry.voxelSize *
           passRadiusScale(pass, c_.cfg.alpha) * scale / std::sqrt(float(roundsOf(pass)));
}

// New photons (a fresh range of paths) with the pass's shrunk kernels; the probe's pass traces
// its indirect kernels at scale 1 and scales its parts itself.
PhotonMap SplatPasses::tracePhotonsOf(int pass, int round, PhotonSettings& passSettings) {
    Timer t;
    photons_.firstPath = firstPathOf(pass, round);
    photons_.radiusScale = passRadiusScale(pass, c_.cfg.alpha);
    photons_.rounds = roundsOf(pass);
    passSettings = photons_;
    if (probing_ && pass == 0 && round == 0) passSettings.classScale[kPhotonIndirect] = 1.f;
    PhotonMap photons = tracePhotons(c_.scene, c_.accel, c_.lights, passSettings, c_.pool, c_.reporter);
    c_.stats.addTime("photons", t.seconds());
    photons.report(c_.stats);
    c_.stats.setCount("photon_passes_traced", ++traced_);
    totals_.photonsStored += int64_t(photons.rays.size());
    totals_.photonMb = std::max(totals_.photonMb, double(photons.bytes()) / kMB);
    return photons;
}

// The pass's photons from the store, traced (with every kernel's coverage and edges) when it has
// none yet. The coverage of a kernel is a function of the ray alone (seed, pass, ray), so
// measuring it for every photon here gives each frame the light the splat's own measurement would.
PhotonMap SplatPasses::storedPhotonsOf(int pass, int round, PhotonSettings& passSettings) {
    const int key = pass * RenderConfig::kMaxPhotonRounds + round;
    auto it = store_->passes.find(key);
    if (it == store_->passes.end()) {
        PhotonMap photons = tracePhotonsOf(pass, round, passSettings);
        if (measuresCoverage_) {
            Timer t;
            coverage_.pass = uint64_t(pass);
            normalizeKernelCoverage(c_.accel, photons, coverage_, c_.pool, c_.reporter, &totals_.coverage);
            c_.stats.addTime("coverage", t.seconds());
        }
        ++store_->traced;
        it = store_->passes.emplace(key, std::move(photons)).first;
    } else {  // the settings tracePhotonsOf gave them
        photons_.firstPath = firstPathOf(pass, round);
        photons_.radiusScale = passRadiusScale(pass, c_.cfg.alpha);
        photons_.rounds = roundsOf(pass);
        passSettings = photons_;
    }
    c_.stats.setCount("photon_store_mb", store_->bytes() / kMB);
    return it->second;
}

double SplatPasses::render(const PassShare& share, FixedFilm& sum, const Deadline& deadline) {
    Timer t;
    const int pass = share.pass;
    EyePass eye = traceEye(pass, deadline);
    Timer trees;
    OcclusionTreeStats ts;
    PassTargets targets(c_.accel, *grid_, eye.samples, c_.width, c_.height, receiverSpacing(pass), c_.pool, c_.reporter,
                        c_.ranks, &ts);
    c_.stats.addTime("tree", trees.seconds());
    c_.stats.setCount("receivers", double(targets.receivers()));
    ts.report(c_.stats);
    if (pass == 0 && ts.samplesOutside > 0)
        c_.reporter.warn(c_.scene.path + ": " + std::to_string(ts.samplesOutside) + " eye samples lie outside the grid and get no light");
    if (pass == 0) eyeAndTrees_ = t.seconds(), photonsBegan_ = whole_.seconds();
    if (!replaying_ && share.share == 0) sum.add(eye.film);  // the eye pass's own light: emission, albedo, normal, direct
    // Its photon rounds, each new paths splatted on the same eye samples, until the deadline
    // less the time the receivers' gather after them takes.
    const double gather = deadline.clock ? targets.gatherSeconds() : 0.0;
    const std::function<bool(double)> lacks = lacksFor(share, Deadline{deadline.clock, deadline.seconds - gather});
    // Their indirect photons' receivers are gathered once, after the last.
    const int rounds = roundsOf(pass);
    std::vector<int64_t> sums;
    double needs = 0.0;
    for (int round = 0; round < rounds; ++round) {
        PhotonSettings passSettings;
        PhotonMap photons = store_ ? storedPhotonsOf(pass, round, passSettings) : tracePhotonsOf(pass, round, passSettings);
        if (replaying_) replayRay(photons, passSettings);
        const double before = t.seconds();
        const double splat = splatPass(pass, round, share, targets, eye, std::move(photons), passSettings, sum,
                                       {lacks, gather}, rounds > 1 ? &sums : nullptr);
        if (round == 0) needs = before + splat;
        if (round + 1 < rounds && lacks && lacks(0.0)) break;
    }
    c_.stats.setCount("photon_rounds", rounds);
    if (rounds > 1) {
        Timer gathering;
        targets.gather({&sums}, {&sum}, splat_);
        c_.stats.addTime("splat", gathering.seconds());
    }
    return needs;
}

// At rank 0, told to the others: the later passes' rounds, from the probe's plan, the first
// pass's eye pass and trees, and its photons' seconds apart from the indirect ones' splat.
int SplatPasses::chooseRounds(PhotonRoundsPlan plan, double photonsBefore) {
    plan.eyeSeconds = eyeAndTrees_;
    plan.roundSeconds += photonsBefore;
    double rounds = c_.ranks.rank() == 0 ? choosePhotonRounds(plan) : 1.0;
    c_.ranks.broadcast(&rounds, 1);
    return int(rounds);
}

int SplatPasses::roundsOf(int pass) const {
    if (replaying_) return 1;
    if (c_.cfg.photonRounds > 0) return c_.cfg.photonRounds;
    return pass == 0 ? 1 : rounds_;
}

// The photons' light (this rank's share of them) into `sum`, until the deadline; the probe's pass
// splats its indirect photons apart, at the scales it measures. Returns half the seconds a
// whole splat takes.
double SplatPasses::splatPass(int pass, int round, const PassShare& share, PassTargets& targets, const EyePass& eye, PhotonMap photons,
                              const PhotonSettings& passSettings, FixedFilm& sum, const SplatTime& time,
                              std::vector<int64_t>* sums) {
    const std::function<bool()> timeUp = time.timeUp();
    Timer t;
    coverage_.pass = uint64_t(pass);
    splat_.share = share.share;
    splat_.shares = share.shares;
    const bool probe = probing_ && pass == 0 && round == 0 && !replaying_;
    PhotonMap indirect;
    if (probe) {
        auto begin = std::stable_partition(photons.rays.begin(), photons.rays.end(),
                                           [](const PhotonRay& r) { return r.cls != kPhotonIndirect; });
        indirect.rays.assign(begin, photons.rays.end());
        photons.rays.erase(begin, photons.rays.end());
    }
    const uint64_t coveredOthers = targets.splat(photons, splat_, sum, &totals_.splat, &totals_.coverage, timeUp, sums);
    uint64_t coveredIndirect = coveredOthers;
    if (probe) {
        KernelScaleProbeStep step(c_, targets, eye, splat_, totals_);
        const double photonsBefore = whole_.seconds() - photonsBegan_;  // traced, the other classes splatted
        const float m = step.run(indirect, passSettings, sum, whole_, whole_.seconds(), time, coveredIndirect);
        probeWidened_ = step.widened();
        nextPass_ = step.nextSeconds();
        if (c_.cfg.photonRoundsAuto()) rounds_ = chooseRounds(step.roundsPlan(), photonsBefore);
        photons_.classScale[kPhotonIndirect] = m;
        char line[160];
        std::snprintf(line, sizeof line, "indirect kernels at scale %.3g, from the bias and noise the first pass measured", m);
        c_.reporter.info(line);
    }
    double shares[3];
    classShares(photons, coveredOthers, coveredIndirect, shares);
    // The direct film counts once a pass; direct photons (--direct photons) once a round.
    if (round > 0 && photons.pathsFor[kPhotonDirect] <= 0) shares[kPhotonDirect] = 0.0;
    if (!replaying_ && share.share == 0) sum.countPhotonPass(shares);  // a shared pass counts once
    const double seconds = t.seconds();
    c_.stats.addTime("splat", seconds);
    report();
    return kWorthStarting * seconds / std::max(shares[kPhotonIndirect], 0.05);
}

// Whether the deadline will have passed in so many seconds, asked after each portion of a splat
// (none without a time limit). In a pass the ranks share, rank 0's clock decides for all of them.
std::function<bool(double)> SplatPasses::lacksFor(const PassShare& share, const Deadline& deadline) const {
    if (!deadline.clock) return nullptr;
    if (share.shares == 1) return [deadline](double after) { return deadline.passed(after); };
    return [this, deadline](double after) { return agreeOrStop(c_.ranks, deadline.passed(after)); };
}

// --photon: the replayed ray alone, as the full render splats it, and its record reported.
void SplatPasses::replayRay(PhotonMap& photons, const PhotonSettings& passSettings) {
    const PhotonRay traced = replayedRay(c_, photons);
    const PhotonRay ray = probing_ && c_.cfg.replayPass == 0
                              ? KernelScaleProbeStep::asSplatted(c_, photons, size_t(c_.cfg.replayIndex),
                                                                 photons_.classScale[kPhotonIndirect], probeWidened_,
                                                                 passSettings)
                              : traced;
    photons.rays.assign(1, ray);
    PhotonRay covered = ray;  // as the splat will cover it
    CoverageStats unused;
    coverage_.pass = uint64_t(c_.cfg.replayPass);
    KernelEdge edge;
    if (measuresCoverage_) normalizeCoverage(c_.accel, covered, coverage_, unused, &edge);
    reportReplayed(c_, traced, covered, grid_->geometry.voxelSize, edge.lines);
}

void SplatPasses::replay(FixedFilm& sum) {
    if (probing_) {  // the scale, as the render's first pass chooses it
        FixedFilm unused(c_.width, c_.height);
        render(PassShare{0, 0, 1}, unused, Deadline{});
        totals_ = SplatTotals();
    }
    replaying_ = true;
    render(PassShare{c_.cfg.replayPass, 0, 1}, sum, Deadline{});
    c_.reporter.info("photon ray " + std::to_string(c_.cfg.replayIndex) + " reached " +
                     std::to_string(int64_t(c_.stats.count("splat_contributions"))) + " eye samples");
}

void SplatPasses::report() {
    Stats& stats = c_.stats;
    stats.setCount("photon_mb", totals_.photonMb);
    stats.setCount("photons_stored", double(totals_.photonsStored));
    stats.setCount("radius_scale", photons_.radiusScale);
    stats.setCount("kernel_scale", photons_.classScale[kPhotonIndirect]);
    totals_.splat.report(stats);
    if (measuresCoverage_) totals_.coverage.report(stats);
}

}  // namespace rs
