// The pipeline, in order (DESIGN §1):
//   scene → Embree BVH + light sampler
//   splat methods: eye pass → occlusion grid (voxelizer or cache) → occlusion tree →
//                  passes of (photon tracing → splatting) → film
//   path:          passes of path tracing → film
// Stages take their inputs as const& and return their outputs by value; only this file
// knows the order. Every stage's wall time and counts go to Stats (--stats-json, EXR header).
#include "render.h"

#include <cstdio>

#include "accel.h"
#include "eye.h"
#include "grid_stage.h"
#include "kdtree.h"
#include "lights.h"
#include "parallel.h"
#include "path.h"
#include "photons.h"
#include "splat.h"

#ifndef RAYSPLAT_VERSION
#define RAYSPLAT_VERSION "dev"
#endif

namespace rs {

const char* versionString() { return RAYSPLAT_VERSION; }

namespace {

constexpr double kMB = 1024.0 * 1024.0;

// Progressive rendering: passes until the time limit (at least one), averaged. The time goes
// to `stage` when given (else the pass records its own stages).
template <class RenderPass>
Film renderPasses(int width, int height, double timeLimit, Stats& stats, const char* stage, RenderPass&& pass,
                  int& passes) {
    Timer t;
    Film sum(width, height);
    passes = 0;
    double longest = 0.0;
    do {
        Timer one;
        sum.add(pass(passes));
        ++passes;
        longest = std::max(longest, one.seconds());
    } while (timeLimit > 0.0 && t.seconds() + longest <= timeLimit);
    sum.scale(1.f / float(passes));
    if (stage) stats.addTime(stage, t.seconds());
    stats.setCount("passes", passes);
    return sum;
}

Film renderPath(const Scene& scene, const RayAccel& accel, const LightSampler& lights, const Camera& camera,
                int width, int height, const RenderConfig& cfg, ThreadPool& pool, Reporter& reporter, Stats& stats) {
    const int spp = cfg.samplesPerPixel();
    int passes = 0;
    Timer t;
    Film film = renderPasses(width, height, cfg.timeLimit, stats, "render", [&](int pass) {
        return renderPathPass(scene, accel, lights, camera, width, height, cfg, {pass * spp, spp}, pool, reporter);
    }, passes);
    stats.setCount("samples_per_pixel", double(passes) * spp);
    stats.setCount("paths_per_second", double(width) * height * passes * spp / std::max(t.seconds(), 1e-9));
    return film;
}

Film renderSplat(const Scene& scene, const RayAccel& accel, const LightSampler& lights, const Camera& camera,
                 int width, int height, const RenderConfig& cfg, ThreadPool& pool, Reporter& reporter, Stats& stats,
                 StagedFiles* outputs) {
    // Eye pass: where photon energy can land (DESIGN §4).
    Timer t;
    EyePassSettings es;
    es.width = width;
    es.height = height;
    es.spp = cfg.samplesPerPixel();
    es.maxSpecularDepth = cfg.maxDepth;
    es.seed = cfg.seed;
    EyePass eye = traceEyePass(scene, accel, camera, es, pool, reporter);
    stats.addTime("eye", t.seconds());
    stats.setCount("eye_samples", double(eye.samples.size()));
    stats.setCount("eye_samples_mb", eye.samples.bytes() / kMB);

    // Occlusion grid and the tree over it (DESIGN §5–7). Without visibility the tree indexes
    // the eye samples over an empty grid: nothing occludes.
    OcclusionGrid grid = buildGrid(scene, cfg, pool, reporter, stats, outputs);
    t = Timer();
    OcclusionTreeStats ts;
    OcclusionTree tree = buildOcclusionTree(cfg.method == Method::SplatNoVis ? OcclusionGrid(grid.geometry) : grid,
                                            eye.samples, pool, &ts);
    grid = OcclusionGrid();  // the tree holds what the splat needs
    stats.addTime("tree", t.seconds());
    stats.setCount("tree_nodes", double(ts.nodes));
    stats.setCount("tree_nodes_empty", double(ts.empty));
    stats.setCount("tree_nodes_split", double(ts.split));
    stats.setCount("tree_nodes_occlusion", double(ts.occlusion));
    stats.setCount("tree_nodes_visible", double(ts.visible));
    stats.setCount("tree_depth", double(ts.depth));
    stats.setCount("tree_mb", ts.bytes / kMB);
    if (ts.samplesOutside > 0)
        reporter.warn(scene.path + ": " + std::to_string(ts.samplesOutside) + " eye samples lie outside the grid and get no light");

    // Photons and splatting, in passes of fresh sequence ranges (DESIGN §8–9).
    PhotonSettings ps;
    ps.photons = cfg.photons;
    for (int c = 0; c < kPhotonClassCount; ++c) {
        ps.split[c] = cfg.split[c];
        ps.k[c] = cfg.kernelPhotons[c];
        ps.minRadius[c] = cfg.minRadius[c];
        ps.maxRadius[c] = cfg.maxRadius[c];
    }
    ps.voxelSize = tree.geometry.voxelSize;
    ps.maxDepth = cfg.maxDepth;
    ps.seed = cfg.seed;
    SplatSettings splat;
    splat.visibility = cfg.method == Method::Splat;
    double photonMb = 0.0;
    int64_t stored = 0;
    SplatStats ss;
    int passes = 0;
    Film light = renderPasses(width, height, cfg.timeLimit, stats, nullptr, [&](int pass) {
        Timer tp;
        ps.firstPath = uint64_t(pass) << 40;
        PhotonMap photons = tracePhotons(scene, accel, lights, ps, pool, reporter);
        stats.addTime("photons", tp.seconds());
        stored += int64_t(photons.rays.size());
        photonMb = std::max(photonMb, photons.bytes() / kMB);
        for (int c = 0; c < kPhotonClassCount; ++c)
            stats.setCount(std::string("photons_") + photonClassName(c), double(photons.count[c]));
        stats.setCount("photon_paths", double(photons.pathsTraced));
        Timer tsplat;
        Film f(width, height);
        splatPhotons(scene, accel, tree, eye.samples, photons, splat, f, pool, reporter, &ss);
        stats.addTime("splat", tsplat.seconds());
        return f;
    }, passes);
    stats.setCount("photon_mb", photonMb);
    stats.setCount("photons_stored", double(stored));
    stats.setCount("splat_contributions", double(ss.contributions));
    stats.setCount("traversal_nodes", double(ss.traversal.nodes));
    stats.setCount("splat_visibility_rays", double(ss.visibilityRays));
    stats.setCount("splat_refused_behind_origin", double(ss.refused[SegmentReceivers::kBehindOrigin]));
    stats.setCount("splat_refused_hidden", double(ss.refused[SegmentReceivers::kHidden]));

    // The film: emission, albedo and normal from the eye pass, the rest from the photons.
    for (int l = 0; l < kLayerCount; ++l)
        if (l != kEmission) eye.film.layers[l] = std::move(light.layers[l]);
    return std::move(eye.film);
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
