// The pipeline, in order (docs/design.md §1):
//   scene → Embree BVH + light sampler
//   splat methods: occlusion grid (voxelizer or cache), then passes of (splat_pass.h)
//                  (eye pass [+ direct film] → receivers and occlusion trees → photon tracing
//                  → splatting, with the kernels' coverage) → film, the passes averaged
//   path:          passes of path tracing → film
// Stages take their inputs as const& and return their outputs by value; only this file and
// splat_pass.cpp know the order. Every stage's wall time and counts go to Stats (--stats-json,
// EXR header).
#include "render.h"

#include <algorithm>
#include <cstdio>
#include <functional>

#include "core/error.h"
#include "core/simd.h"
#include "core/stop.h"
#include "grid/grid_stage.h"
#include "memory.h"
#include "path/path.h"
#include "ranks.h"
#include "render_context.h"
#include "scene/accel.h"
#include "scene/environment.h"
#include "scene/lights.h"
#include "splat_pass.h"

#ifndef RAYSPLAT_VERSION
#define RAYSPLAT_VERSION "dev"
#endif

namespace rs {

const char* versionString() { return RAYSPLAT_VERSION; }

Ranks& singleProcess() {
    static Ranks one;
    return one;
}

bool agreeOrStop(Ranks& ranks, bool more) {
    const Ranks::Agreement a = ranks.agree(true, more);
    if (a.failedRank >= 0)
        throw Error(ErrorKind::OtherRank, "rank " + std::to_string(a.failedRank) + " failed");
    return a.more;
}

namespace {

PathSettings pathSettings(const RenderContext& c) {
    PathSettings ps;
    ps.width = c.width;
    ps.height = c.height;
    ps.spp = c.cfg.samplesPerPixel();
    ps.maxDepth = c.cfg.maxDepth;
    ps.seed = c.cfg.seed;
    return ps;
}

// Progressive rendering: cfg.passCount() passes, or with a time limit as many as fit (at least
// one), averaged with equal weights, summed in fixed point. With several ranks
// (docs/design.md §11) passes go round by round, one pass a rank, pass p to rank p mod N; with
// fewer passes than ranks every rank renders a share of every pass. After each round the
// ranks agree: on errors, and (rank 0's clock) on whether another round fits the time limit.
// With firstShared the first pass is rendered by every rank, a share each, before any other:
// what it measures decides the passes after it (the kernel scale), and it may say how long
// they will take (nextSeconds > 0, at rank 0). A pass is handed the deadline (none without a
// time limit) and returns the seconds a pass needs to be worth starting: a whole pass of the
// path tracer's; a splat pass stops early at the deadline with an unbiased share of its photons
// (docs/design.md §9), so that is less than its whole time.
// A pass of the eye film alone: pass `pass`'s film samples into the sum; returns its seconds.
using FilmPass = std::function<double(int pass, FixedFilm& sum)>;

// Passes of the eye film alone (docs/design.md §9) after the `first` passes, in rounds of one a
// rank: cfg.filmPasses of them, or under a time limit as many as rank 0's clock says fit in the
// time the whole passes left, each taking at most `estimate` seconds until one is timed.
// Returns how many.
int renderFilmPasses(const RenderContext& c, const FilmPass& filmPass, double estimate, const Timer& t, int first,
                     FixedFilm& sum) {
    const bool timed = c.cfg.timeLimit > 0.0;
    const int ranks = c.ranks.size(), me = c.ranks.rank();
    double longest = estimate;
    int done = 0;
    auto more = [&] {
        return timed ? longest > 0.0 && t.seconds() + longest <= c.cfg.timeLimit && first + done + ranks <= c.cfg.maxPasses()
                     : done < c.cfg.filmPasses;
    };
    while (agreeOrStop(c.ranks, more())) {
        throwIfStopped();
        const int round = timed ? ranks : std::min(ranks, c.cfg.filmPasses - done);
        if (me < round) {
            const double seconds = filmPass(first + done + me, sum);
            longest = done == 0 ? seconds : std::max(longest, seconds);
        }
        done += round;
    }
    return done;
}

template <class RenderPass>
Film renderPasses(const RenderContext& c, RenderPass&& pass, bool firstShared = false, const double* nextSeconds = nullptr,
                  const FilmPass& filmPass = nullptr, const double* filmSeconds = nullptr) {
    Timer t;
    const Deadline deadline = c.cfg.timeLimit > 0.0 ? Deadline{&t, c.cfg.timeLimit} : Deadline{};
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
        double needs = 0.0;
        if (together)
            needs = pass(PassShare{passes, me, ranks}, sum, deadline);
        else if (me < round)
            needs = pass(PassShare{passes + me, 0, 1}, sum, deadline);
        // The first round's time counts until a second one is timed: it measured for the others.
        longest = passes == 0 || (firstShared && passes == 1) ? needs : std::max(longest, needs);
        if (firstShared && passes == 0 && nextSeconds && *nextSeconds > 0.0) longest = *nextSeconds;
        passes += round;
        if (several) c.reporter.advance(round);
        // Under a time limit, also no further than the passes whose sample indices fit (maxPasses).
        more = agreeOrStop(c.ranks, timed ? t.seconds() + longest <= c.cfg.timeLimit && passes + ranks <= c.cfg.maxPasses()
                                          : passes < wanted);
    }
    const int filmPasses = filmPass && (timed || c.cfg.filmPasses > 0)
                               ? renderFilmPasses(c, filmPass, *filmSeconds, t, passes, sum) : 0;
    if (several) c.reporter.end();
    for (std::vector<int64_t>& buffer : sum.buffers) c.ranks.sumAtRoot(buffer);
    std::vector<int64_t> counted(sum.photonPasses, sum.photonPasses + 3);
    counted.push_back(sum.filmPasses);
    c.ranks.sumAtRoot(counted);
    std::copy(counted.begin(), counted.begin() + 3, sum.photonPasses);
    sum.filmPasses = counted[3];
    const std::vector<int64_t>& photonPasses = counted;
    c.stats.setCount("passes", passes);
    if (filmPass) c.stats.setCount("film_passes", filmPasses);
    if (photonPasses[kIndirect] > 0) c.stats.setCount("photon_passes", double(photonPasses[kIndirect]) / FixedFilm::kScale);
    // The image is rank 0's; the others have nothing left to do that could fail.
    return me == 0 ? sum.average(passes) : Film();
}

Film renderPath(const RenderContext& c) {
    PathSettings ps = pathSettings(c);
    const int spp = ps.spp;
    int passes = 0;
    Timer t;
    Film film = renderPasses(c, [&](const PassShare& share, FixedFilm& sum, const Deadline&) {
        Timer one;
        passes = std::max(passes, share.pass + 1);
        ps.firstSample = share.pass * spp;
        ps.rowBegin = c.height * share.share / share.shares;
        ps.rowEnd = c.height * (share.share + 1) / share.shares;
        sum.add(renderPathPass(c.scene, c.accel, c.lights, c.camera, ps, c.pool, c.reporter));
        return one.seconds();
    });
    c.stats.addTime("render", t.seconds());
    c.stats.setCount("samples_per_pixel", double(passes) * spp);
    c.stats.setCount("paths_per_second", double(c.width) * c.height * passes * spp / std::max(t.seconds(), 1e-9));
    return film;
}

// Photon ray splatting: the grid once, then the passes (splat_pass.h); the first pass alone, on
// every rank a share, where it measures the kernel scale for the others.
Film renderSplat(const RenderContext& c, StagedFiles* outputs, PhotonStore* store) {
    SplatPasses passes(c, outputs, store);
    if (c.cfg.replays()) {
        FixedFilm sum(c.width, c.height);
        passes.replay(sum);
        return c.ranks.rank() == 0 ? sum.average(1) : Film();
    }
    const FilmPass filmPass = passes.filmOnly() ? FilmPass([&](int pass, FixedFilm& sum) { return passes.renderFilm(pass, sum); })
                                                : nullptr;
    return renderPasses(
        c, [&](const PassShare& share, FixedFilm& sum, const Deadline& deadline) { return passes.render(share, sum, deadline); },
        passes.probing(), passes.nextSeconds(), filmPass, passes.eyeSeconds());
}

}  // namespace

// The scene's part of a render: everything but the camera's.
struct PreparedScene::Parts {
    Parts(const Scene& s, const RenderConfig& c, Reporter& r, Ranks& k) : scene(s), cfg(c), reporter(r), ranks(k) {}
    const Scene& scene;
    const RenderConfig& cfg;
    Reporter& reporter;
    Ranks& ranks;
    int width = 0, height = 0;
    Stats stats;  // the setup's figures, copied into every view's
    std::unique_ptr<ThreadPool> pool;
    std::unique_ptr<RayAccel> accel;
    std::unique_ptr<Environment> environment;
    std::unique_ptr<LightSampler> lights;
};

PreparedScene::PreparedScene(const Scene& scene, const RenderConfig& cfg, Reporter& reporter, Ranks& ranks, bool keepsPhotons)
    : parts_(new Parts(scene, cfg, reporter, ranks)) {
    cfg.validate();
    Parts& p = *parts_;
    Stats& stats = p.stats;
    const Camera camera = scene.camera(cfg.camera);
    cfg.resolution(camera.aspect, p.width, p.height);
    // Refuse settings the machine cannot hold before allocating anything large.
    const GridGeometry geometry = cfg.splats() || !cfg.vdb.empty() || !cfg.cacheDir.empty()
                                      ? gridForBounds(scene.bounds, cfg.grid)
                                      : GridGeometry();
    const int gridDims[3] = {geometry.dims.x, geometry.dims.y, geometry.dims.z};
    const int threads = cfg.threads > 0 ? cfg.threads : ThreadPool::hardwareThreads();
    const MemoryEstimate memory = estimateMemory(cfg, gridDims, scene.triangleCount(), p.width, p.height, threads, keepsPhotons);
    checkMemory(memory, cfg.maxMemory, ranks.sizeOnThisMachine());
    stats.setCount("memory_estimate_mb", memory.total() / kMB);
    agreeOrStop(ranks, false);  // every rank got this far: the scene loaded and fits

    p.pool = std::make_unique<ThreadPool>(cfg.threads);
    stats.setCount("threads", p.pool->size());
    stats.setCount("ranks", ranks.size());
    stats.setCount("simd_lanes", int(traversalIsa()));  // the occlusion tree traversal's: 4 (sse2) or 16 (avx512)
    stats.setCount("triangles", double(scene.triangleCount()));
    double textureBytes = 0.0;
    for (const Texture& t : scene.textures) textureBytes += double(t.bytes());
    stats.setCount("texture_mb", textureBytes / kMB);  // texels of every mip level
    stats.setCount("width", p.width);
    stats.setCount("height", p.height);

    // Ray-tracing acceleration structure and the lights.
    Timer t;
    p.accel = std::make_unique<RayAccel>(scene, p.pool->size());
    p.environment = std::make_unique<Environment>(cfg.environment(scene));
    p.lights = std::make_unique<LightSampler>(scene, p.environment.get());
    stats.addTime("bvh", t.seconds());
    if (p.lights->empty()) reporter.warn(scene.path + ": the scene has no lights and no environment: the image will be black");
}

PreparedScene::~PreparedScene() = default;

RenderResult PreparedScene::render(const Camera& camera, PhotonStore* store) {
    const Parts& p = *parts_;
    const RenderConfig& cfg = p.cfg;
    RenderResult result;
    result.stats = p.stats;
    // How many views shared the setup before this one: 0 where it was built for this one.
    result.stats.setCount("bvh_reused", views_++);
    const RenderContext context{p.scene, *p.accel, *p.lights, camera, p.width, p.height, cfg, *p.pool, p.reporter, result.stats, p.ranks};
    if (cfg.splats()) {
        result.film = renderSplat(context, result.outputs.get(), store);
    } else {
        // The path tracer does not need the grid; it is built only when asked for.
        if (!cfg.vdb.empty() || !cfg.cacheDir.empty())
            buildGrid(p.scene, cfg.gridSettings(), *p.pool, p.reporter, result.stats, result.outputs.get());
        result.film = renderPath(context);
    }

    result.attributes = cfg.attributes();
    result.attributes["scene"] = p.scene.path;
    result.attributes["version"] = versionString();
    result.attributes["simd"] = isaName(traversalIsa());
    if (cfg.splats() && cfg.probesKernelScale() && !cfg.replays() && !store)
        result.attributes["kernelScale"] = "auto: " + std::to_string(result.stats.count("kernel_scale"));
    else if (cfg.splats() && store && cfg.kernelScale <= 0.f)
        result.attributes["kernelScale"] = "1";  // stored photons are not probed
    if (!cfg.splats()) result.attributes["spp"] = std::to_string(int64_t(result.stats.count("samples_per_pixel")));
    for (const auto& [stage, s] : result.stats.seconds) {
        char b[32];
        std::snprintf(b, sizeof b, "%.4f", s);
        result.attributes["time." + stage] = b;
    }
    return result;
}

RenderResult render(const Scene& scene, const RenderConfig& cfg, Reporter& reporter, Ranks& ranks, PhotonStore* store) {
    return PreparedScene(scene, cfg, reporter, ranks).render(scene.camera(cfg.camera), store);
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
