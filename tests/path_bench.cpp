// Path tracer throughput on the Cornell box at 500×500: paths per second, median of 3 runs.
// Run with `meson test --benchmark path_tracer` or directly.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/parallel.h"
#include "render.h"

int main() {
    const char* data = std::getenv("RAYSPLAT_DATA");
    std::string path = std::string(data ? data : "data") + "/cornell_box.gltf";
    rs::Scene scene = rs::loadScene(path, rs::silentReporter());
    rs::RenderConfig cfg;
    cfg.output = "unused.exr";
    cfg.method = rs::Method::Path;
    cfg.width = 500;
    cfg.spp = 16;
    std::vector<double> rates;
    for (int run = 0; run < 3; ++run) {
        rs::RenderResult r = rs::render(scene, cfg, rs::silentReporter());
        double seconds = r.stats.time("render");
        rates.push_back(500.0 * 500.0 * cfg.spp / seconds);
        std::printf("run %d: %.3f s, %.0f paths/s\n", run + 1, seconds, rates.back());
    }
    std::sort(rates.begin(), rates.end());
    std::printf("path tracer, cornell_box 500x500x%d, %d threads: median %.3g paths/s\n", cfg.spp,
                rs::ThreadPool::hardwareThreads(), rates[1]);
    return 0;
}
