// Grid stage: cache lookup, voxelizer choice, .vdb output (see grid_stage.h). OpenVDB stays
// behind vdb_io.h.
#include "grid/grid_stage.h"

#include <cstdio>
#include <filesystem>

#include "core/error.h"
#include "grid/gpu_context.h"
#include "grid/vdb_io.h"
#include "grid/voxelize.h"

namespace rs {

std::string cachePath(const std::string& cacheDir, const std::string& key) {
    return (std::filesystem::path(cacheDir) / (key + ".vdb")).string();
}

namespace {

bool sameGeometry(const GridGeometry& a, const GridGeometry& b) {
    return a.dims == b.dims && a.voxelSize == b.voxelSize && a.origin == b.origin;
}

// The cached grid for `key`, if the file is there and is the grid we would compute.
bool loadCached(const std::string& path, const std::string& key, const GridGeometry& geometry, Reporter& reporter,
                OcclusionGrid& out) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return false;
    VdbFile cached;
    try {
        cached = readCacheVdb(path);
    } catch (const Error& e) {
        reporter.warn(std::string(e.what()) + "; voxelizing again and replacing the cache file");
        return false;
    }
    if (cached.metadata.cacheKey != key || !sameGeometry(cached.grid.geometry, geometry) ||
        cached.metadata.supersampling != kVoxelizerSupersampling) {
        reporter.warn(path + ": stale cache file (its key or grid geometry does not match the scene); "
                      "voxelizing again and replacing it");
        return false;
    }
    out = std::move(cached.grid);
    return true;
}

// "auto": the GPU voxelizer on a hardware EGL device; with none, the CPU voxelizer, which gives
// the same grid faster than EGL's software rasterizer (llvmpipe: 0.21 against 0.07 s for the
// glossy box at 192³ on 2 cores, voxelize_bench).
OcclusionGrid voxelize(const Scene& scene, const GridGeometry& geometry, const std::string& voxelizer,
                       ThreadPool& pool, Reporter& reporter, VoxelizerKind& used) {
    if (voxelizer == "cpu" || (voxelizer == "auto" && !hasHardwareGpu())) {
        used = VoxelizerKind::Cpu;
        return voxelizeCpu(scene, geometry, pool, reporter);
    }
    try {
        used = VoxelizerKind::Gpu;
        return voxelizeGpu(scene, geometry, reporter);
    } catch (const Error& e) {
        if (voxelizer != "auto" || e.kind() != ErrorKind::Gpu) throw;
        reporter.warn(std::string("GPU voxelizer unavailable (") + e.what() + "); using the CPU voxelizer");
    }
    used = VoxelizerKind::Cpu;
    return voxelizeCpu(scene, geometry, pool, reporter);
}

}  // namespace

OcclusionGrid buildGrid(const Scene& scene, const GridSettings& cfg, ThreadPool& pool, Reporter& reporter,
                        Stats& stats, StagedFiles* outputs) {
    if (cfg.voxelizer != "auto" && cfg.voxelizer != "gpu" && cfg.voxelizer != "cpu")
        throw Error(ErrorKind::Config, "voxelizer '" + cfg.voxelizer + "' is not one of auto, gpu, cpu");
    Timer timer;
    const GridGeometry geometry = gridForBounds(scene.bounds, cfg.resolution);

    // Look in the cache, GPU key first: with "auto" either voxelizer may have made the file.
    std::vector<VoxelizerKind> kinds;
    if (cfg.voxelizer != "cpu") kinds.push_back(VoxelizerKind::Gpu);
    if (cfg.voxelizer != "gpu") kinds.push_back(VoxelizerKind::Cpu);
    // Hashing reads every vertex: once per kind.
    std::string keys[2];
    auto keyOf = [&](VoxelizerKind kind) -> const std::string& {
        std::string& k = keys[kind == VoxelizerKind::Gpu ? 0 : 1];
        if (k.empty()) k = cacheKey(scene, cfg.resolution, kind);
        return k;
    };
    OcclusionGrid grid;
    bool hit = false;
    VoxelizerKind used = kinds.front();
    if (!cfg.cacheDir.empty()) {
        for (VoxelizerKind kind : kinds) {
            std::string path = cachePath(cfg.cacheDir, keyOf(kind));
            if (loadCached(path, keyOf(kind), geometry, reporter, grid)) {
                hit = true;
                used = kind;
                reporter.info("loaded the occlusion grid from the cache: " + path);
                break;
            }
        }
    }

    VdbMetadata meta;
    meta.scene = scene.path;
    meta.sceneBounds = scene.bounds;
    if (!hit) {
        grid = voxelize(scene, geometry, cfg.voxelizer, pool, reporter, used);
        if (!cfg.cacheDir.empty()) {
            meta.cacheKey = keyOf(used);
            meta.voxelizer = voxelizerName(used);
            std::string path = cachePath(cfg.cacheDir, meta.cacheKey);
            try {
                std::error_code ec;
                std::filesystem::create_directories(cfg.cacheDir, ec);
                writeCacheVdb(path, grid, meta);
            } catch (const Error& e) {
                reporter.warn(std::string(e.what()) + " (the voxel cache is not updated)");
            }
        }
    }
    meta.cacheKey = keyOf(used);
    meta.voxelizer = voxelizerName(used);
    if (!cfg.vdb.empty()) {
        if (outputs) writeVdbTo(outputs->stage(cfg.vdb), cfg.vdb, grid, meta);
        else writeVdb(cfg.vdb, grid, meta);
    }

    stats.addTime("voxelize", timer.seconds());
    stats.setCount("voxels", double(geometry.voxelCount()));
    stats.setCount("occupied_voxels", double(grid.occupiedCount()));
    stats.setCount("grid_bytes", double(grid.counts.size()));
    stats.setCount("grid_cache_hit", hit ? 1 : 0);
    return grid;
}

}  // namespace rs
