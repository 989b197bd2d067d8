// Voxelizer timings: data/glossy_box.glb at 192 and, when RAYSPLAT_EXTRA_SCENES names a folder
// of scenes from elsewhere, its bitterli-teapot/teapot.glb at 256, GPU (whatever EGL gives: llvmpipe on a CPU
// machine) and CPU, 3 runs each; medians of each stage. Run with
// `meson test --benchmark voxelize` or directly.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "core/error.h"
#include "grid/gpu_context.h"
#include "core/stats.h"
#include "grid/voxelize.h"

namespace {

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

void bench(const std::string& path, int resolution, rs::ThreadPool& pool) {
    if (!std::filesystem::exists(path)) {
        std::printf("%s: absent, skipped\n", path.c_str());
        return;
    }
    rs::Scene scene = rs::loadScene(path, rs::silentReporter());
    rs::GridGeometry grid = rs::gridForBounds(scene.bounds, resolution);
    std::printf("\n%s: %zu triangles, grid %dx%dx%d\n", std::filesystem::path(path).filename().c_str(),
                scene.triangleCount(), grid.dims.x, grid.dims.y, grid.dims.z);
    std::printf("  %-4s %7s %7s %7s %7s %7s %7s  %s\n", "", "setup", "upload", "raster", "readbk", "reduce", "total",
                "occupied voxels (median of 3 runs, seconds)");
    for (rs::VoxelizerKind kind : {rs::VoxelizerKind::Gpu, rs::VoxelizerKind::Cpu}) {
        std::vector<double> setup, upload, raster, readback, reduction, total;
        size_t occupied = 0;
        try {
            for (int run = 0; run < 3; ++run) {
                rs::VoxelizeTimings t;
                rs::Timer timer;
                rs::OcclusionGrid g = kind == rs::VoxelizerKind::Gpu
                                          ? rs::voxelizeGpu(scene, grid, rs::silentReporter(), &t)
                                          : rs::voxelizeCpu(scene, grid, pool, rs::silentReporter());
                total.push_back(timer.seconds());
                setup.push_back(t.setup);
                upload.push_back(t.upload);
                raster.push_back(t.raster);
                readback.push_back(t.readback);
                reduction.push_back(t.reduction);
                occupied = g.occupiedCount();
            }
        } catch (const rs::Error& e) {
            std::printf("  %-4s skipped: %s\n", kind == rs::VoxelizerKind::Gpu ? "gpu" : "cpu", e.what());
            continue;
        }
        if (kind == rs::VoxelizerKind::Gpu)
            std::printf("  %-4s %7.3f %7.3f %7.3f %7.3f %7.3f %7.3f  %zu\n", "gpu", median(setup), median(upload),
                        median(raster), median(readback), median(reduction), median(total), occupied);
        else
            std::printf("  %-4s %7s %7s %7s %7s %7s %7.3f  %zu (%d threads)\n", "cpu", "", "", "", "", "", median(total),
                        occupied, pool.size());
    }
}

}  // namespace

int main() {
    const char* data = std::getenv("RAYSPLAT_DATA");
    const char* extra = std::getenv("RAYSPLAT_EXTRA_SCENES");
    try {
        std::printf("gpu: %s\n", rs::describeGpu().c_str());
    } catch (const rs::Error& e) {
        std::printf("gpu: none (%s)\n", e.what());
    }
    rs::ThreadPool pool(0);
    bench(std::string(data ? data : "data") + "/glossy_box.glb", 192, pool);
    if (extra && *extra) bench(std::string(extra) + "/bitterli-teapot/teapot.glb", 256, pool);
    return 0;
}
