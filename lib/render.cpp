// The pipeline, in order. Today: scene → Embree BVH → light sampler → path tracing passes.
// Stages take their inputs as const& and return their outputs by value; only this file
// knows the order (DESIGN §1).
#include "render.h"

#include <cstdio>

#include "accel.h"
#include "lights.h"
#include "parallel.h"
#include "path.h"

#ifndef RAYSPLAT_VERSION
#define RAYSPLAT_VERSION "dev"
#endif

namespace rs {

const char* versionString() { return RAYSPLAT_VERSION; }

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

    // Ray-tracing acceleration structure.
    Timer t;
    RayAccel accel(scene, pool.size());
    LightSampler lights(scene);
    stats.addTime("bvh", t.seconds());
    if (lights.empty()) reporter.warn(scene.path + ": the scene has no lights: the image will be black");

    // Path tracing: one pass, or passes of cfg.spp until the time limit.
    Timer tp;
    Film sum(width, height);
    int passes = 0;
    double longestPass = 0.0;
    do {
        Timer pass;
        sum.add(renderPathPass(scene, accel, lights, camera, width, height, cfg, {passes * cfg.spp, cfg.spp}, pool, reporter));
        ++passes;
        longestPass = std::max(longestPass, pass.seconds());
    } while (cfg.timeLimit > 0.0 && tp.seconds() + longestPass <= cfg.timeLimit);
    sum.scale(1.f / float(passes));
    stats.addTime("render", tp.seconds());
    stats.setCount("passes", passes);
    stats.setCount("samples_per_pixel", double(passes) * cfg.spp);
    stats.setCount("paths_per_second", double(width) * height * passes * cfg.spp / std::max(tp.seconds(), 1e-9));
    result.film = std::move(sum);

    result.attributes = cfg.attributes();
    result.attributes["scene"] = scene.path;
    result.attributes["version"] = versionString();
    result.attributes["spp"] = std::to_string(passes * cfg.spp);
    for (const auto& [stage, s] : stats.seconds) {
        char b[32];
        std::snprintf(b, sizeof b, "%.4f", s);
        result.attributes["time." + stage] = b;
    }
    return result;
}

void writeOutputs(const RenderResult& result, const RenderConfig& cfg) {
    writeExr(cfg.output, result.film, result.attributes);
    if (!cfg.png.empty()) writePng(cfg.png, result.film, cfg.exposure);
    if (!cfg.statsJson.empty()) writeFileAtomic(cfg.statsJson, result.stats.json());
}

}  // namespace rs
