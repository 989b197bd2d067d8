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

#include "scene/accel.h"
#include "splat/eye.h"
#include "grid/grid_stage.h"
#include "splat/kdtree.h"
#include "scene/lights.h"
#include "core/parallel.h"
#include "path/path.h"
#include "splat/photons.h"
#include "splat/splat.h"

#ifndef RAYSPLAT_VERSION
#define RAYSPLAT_VERSION "dev"
#endif

namespace rs {

const char* versionString() { return RAYSPLAT_VERSION; }

namespace {

constexpr double kMB = 1024.0 * 1024.0;

// Progressive rendering: cfg.passCount() passes, or with a time limit as many as fit (at least
// one), averaged with equal weights. Each pass reports as one unit of the "rendering"
// progress when there is more than one.
template <class RenderPass>
Film renderPasses(const RenderConfig& cfg, int width, int height, Reporter& reporter, Stats& stats, RenderPass&& pass) {
    Timer t;
    Film sum(width, height);
    const bool timed = cfg.timeLimit > 0.0;
    const int wanted = cfg.passCount();
    const bool several = timed || wanted > 1;
    if (several) reporter.begin("rendering", timed ? 0 : wanted, "passes");
    int passes = 0;
    double longest = 0.0;
    for (;;) {
        Timer one;
        sum.add(pass(passes));
        ++passes;
        longest = std::max(longest, one.seconds());
        if (several) reporter.advance(1);
        if (timed ? t.seconds() + longest > cfg.timeLimit : passes >= wanted) break;
    }
    if (several) reporter.end();
    sum.scale(1.f / float(passes));
    stats.setCount("passes", passes);
    return sum;
}

// The kernel scale of pass p (0-based): r²(n+1) = r²(n)·(n + α)/(n + 1) for passes n = 1, 2, …
float passRadiusScale(int p, float alpha) {
    double r2 = 1.0;
    for (int n = 1; n <= p; ++n) r2 *= (n + double(alpha)) / (n + 1.0);
    return float(std::sqrt(r2));
}

Film renderPath(const Scene& scene, const RayAccel& accel, const LightSampler& lights, const Camera& camera,
                int width, int height, const RenderConfig& cfg, ThreadPool& pool, Reporter& reporter, Stats& stats) {
    const int spp = cfg.samplesPerPixel();
    int passes = 0;
    Timer t;
    Film film = renderPasses(cfg, width, height, reporter, stats, [&](int pass) {
        passes = pass + 1;
        return renderPathPass(scene, accel, lights, camera, width, height, cfg, {pass * spp, spp}, pool, reporter);
    });
    stats.addTime("render", t.seconds());
    stats.setCount("samples_per_pixel", double(passes) * spp);
    stats.setCount("paths_per_second", double(width) * height * passes * spp / std::max(t.seconds(), 1e-9));
    return film;
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
    return ps;
}

// Counts a pass's tree and splat add to Stats: the last pass's sizes, every pass's work.
struct SplatTotals {
    SplatStats splat;
    int64_t photonsStored = 0;
    double photonMb = 0.0, eyeMb = 0.0, treeMb = 0.0;
};

Film renderSplat(const Scene& scene, const RayAccel& accel, const LightSampler& lights, const Camera& camera,
                 int width, int height, const RenderConfig& cfg, ThreadPool& pool, Reporter& reporter, Stats& stats,
                 StagedFiles* outputs) {
    // The occlusion grid, once (docs/design.md §5–6). Without visibility the tree indexes the eye
    // samples over an empty grid: nothing occludes.
    OcclusionGrid grid = buildGrid(scene, cfg, pool, reporter, stats, outputs);
    if (cfg.method == Method::SplatNoVis) grid = OcclusionGrid(grid.geometry);

    EyePassSettings es;
    es.width = width;
    es.height = height;
    es.spp = cfg.samplesPerPixel();
    es.maxSpecularDepth = cfg.maxDepth;
    es.directSamples = cfg.directBySampling() ? cfg.lightSamples : 0;
    es.seed = cfg.seed;
    PhotonSettings ps = photonSettings(cfg, grid.geometry.voxelSize);
    SplatSettings splat;
    splat.visibility = cfg.method == Method::Splat;
    SplatTotals totals;

    // Every pass: new eye samples (the next S of each pixel's sequence), the tree over them,
    // new photons (a fresh range of paths) with shrunk kernels, splatted (docs/design.md §4, §7–9).
    return renderPasses(cfg, width, height, reporter, stats, [&](int pass) {
        Timer t;
        es.firstSample = pass * es.spp;
        EyePass eye = traceEyePass(scene, accel, &lights, camera, es, pool, reporter);
        stats.addTime("eye", t.seconds());
        stats.setCount("eye_samples", double(eye.samples.size()));
        stats.setCount("eye_samples_mb", eye.samples.bytes() / kMB);

        t = Timer();
        OcclusionTreeStats ts;
        OcclusionTree tree = buildOcclusionTree(grid, eye.samples, pool, &ts);
        stats.addTime("tree", t.seconds());
        stats.setCount("tree_nodes", double(ts.nodes));
        stats.setCount("tree_nodes_empty", double(ts.empty));
        stats.setCount("tree_nodes_split", double(ts.split));
        stats.setCount("tree_nodes_occlusion", double(ts.occlusion));
        stats.setCount("tree_bricks", double(ts.bricks));
        stats.setCount("tree_brick_voxels", double(ts.brickVoxels));
        stats.setCount("tree_depth", double(ts.depth));
        stats.setCount("tree_mb", ts.bytes / kMB);
        if (pass == 0 && ts.samplesOutside > 0)
            reporter.warn(scene.path + ": " + std::to_string(ts.samplesOutside) + " eye samples lie outside the grid and get no light");

        t = Timer();
        ps.firstPath = uint64_t(pass) << PhotonSettings::kPathsPerPassBits;
        ps.radiusScale = passRadiusScale(pass, cfg.alpha);
        PhotonMap photons = tracePhotons(scene, accel, lights, ps, pool, reporter);
        stats.addTime("photons", t.seconds());
        totals.photonsStored += int64_t(photons.rays.size());
        totals.photonMb = std::max(totals.photonMb, photons.bytes() / kMB);
        for (int c = 0; c < kPhotonClassCount; ++c)
            stats.setCount(std::string("photons_") + photonClassName(c), double(photons.count[c]));
        stats.setCount("photon_paths", double(photons.pathsTraced));

        // The light lands in the eye pass's film: emission, albedo, normal and (sampled)
        // direct light are already there.
        t = Timer();
        splatPhotons(accel, tree, eye.samples, photons, splat, eye.film, pool, reporter, &totals.splat);
        stats.addTime("splat", t.seconds());
        stats.setCount("photon_mb", totals.photonMb);
        stats.setCount("photons_stored", double(totals.photonsStored));
        stats.setCount("radius_scale", ps.radiusScale);
        stats.setCount("splat_contributions", double(totals.splat.contributions));
        stats.setCount("traversal_nodes", double(totals.splat.traversal.nodes));
        stats.setCount("traversal_occluders", double(totals.splat.traversal.occluders));
        stats.setCount("traversal_samples_reached", double(totals.splat.traversal.samplesReached));
        stats.setCount("traversal_samples_visited", double(totals.splat.traversal.samplesVisited));
        stats.setCount("splat_visibility_rays", double(totals.splat.visibilityRays));
        stats.setCount("splat_refused_behind_origin", double(totals.splat.refused[SegmentReceivers::kBehindOrigin]));
        stats.setCount("splat_refused_hidden", double(totals.splat.refused[SegmentReceivers::kHidden]));
        return std::move(eye.film);
    });
}

}  // namespace

RenderResult render(const Scene& scene, const RenderConfig& cfg, Reporter& reporter) {
    cfg.validate();
    RenderResult result;
    Stats& stats = result.stats;
    Camera camera = scene.camera(cfg.camera);
    int width, height;
    cfg.resolution(camera.aspect, width, height);
    ThreadPool pool(cfg.threads);
    stats.setCount("threads", pool.size());
    stats.setCount("triangles", double(scene.triangleCount()));
    stats.setCount("width", width);
    stats.setCount("height", height);

    // Ray-tracing acceleration structure and the lights.
    Timer t;
    RayAccel accel(scene, pool.size());
    LightSampler lights(scene);
    stats.addTime("bvh", t.seconds());
    if (lights.empty()) reporter.warn(scene.path + ": the scene has no lights: the image will be black");

    if (cfg.splats()) {
        result.film = renderSplat(scene, accel, lights, camera, width, height, cfg, pool, reporter, stats,
                                  result.outputs.get());
    } else {
        // The path tracer does not need the grid; it is built only when asked for.
        if (!cfg.vdb.empty() || !cfg.cacheDir.empty()) buildGrid(scene, cfg, pool, reporter, stats, result.outputs.get());
        result.film = renderPath(scene, accel, lights, camera, width, height, cfg, pool, reporter, stats);
    }

    result.attributes = cfg.attributes();
    result.attributes["scene"] = scene.path;
    result.attributes["version"] = versionString();
    if (!cfg.splats()) {
        for (const auto& [name, v] : stats.counts)
            if (name == "samples_per_pixel") result.attributes["spp"] = std::to_string(int64_t(v));
    }
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
    writeExrTo(out.stage(cfg.output), cfg.output, result.film, result.attributes);
    if (!cfg.png.empty()) writeFileTo(out.stage(cfg.png), cfg.png, encodePng(result.film, cfg.exposure));
    if (!cfg.statsJson.empty()) writeFileTo(out.stage(cfg.statsJson), cfg.statsJson, result.stats.json());
    out.commit();
}

}  // namespace rs
