// Grid stage (docs/design.md §5–6): Scene → OcclusionGrid, through the voxel cache when there is one.
//
// Takes the scene (glTF world) and the GridSettings (validated by the caller: RenderConfig);
// returns the OcclusionGrid over gridForBounds(scene.bounds, settings.resolution).
//  - With a cache directory: looks for <cacheDir>/<cacheKey>.vdb and loads it when its metadata
//    key and grid geometry match; a stale or unreadable cache file is recomputed with a
//    warning and rewritten. With --voxelizer auto the GPU key is tried first, then the
//    CPU key (auto uses the CPU without a hardware EGL device, or after the GPU failed).
//  - Otherwise voxelizes: "gpu" (Error(Gpu) without EGL), "cpu", or "auto" (the GPU when EGL
//    lists a hardware device, falling back to the CPU with a warning when it is unusable;
//    the CPU at once when EGL offers only a software device such as llvmpipe).
//  - Writes the .vdb file when one is named (an error there is an error of the run; a cache file that
//    cannot be written is only a warning).
// Records the time "voxelize" (the whole stage, load or compute) and the counts "voxels",
// "occupied_voxels", "grid_bytes", "grid_cache_hit" (0/1).
#pragma once

#include <string>

#include "core/log.h"
#include "grid/occlusion_grid.h"
#include "core/parallel.h"
#include "scene/scene.h"
#include "core/stats.h"
#include "core/staged_files.h"

namespace rs {

struct GridSettings {
    int resolution = 192;            // voxels along the scene's longest axis, 1..kMaxGridResolution
    std::string voxelizer = "auto";  // auto (GPU on a hardware EGL device, else CPU), gpu, cpu
    std::string vdb;                 // optional: write the grid used as .vdb
    std::string cacheDir;            // optional: voxel cache directory (<key>.vdb files)
};

// With `outputs`, the .vdb is staged there (committed with the render's other outputs);
// without, it is written atomically right away.
OcclusionGrid buildGrid(const Scene& scene, const GridSettings& settings, ThreadPool& pool, Reporter& reporter,
                        Stats& stats, StagedFiles* outputs = nullptr);

// The cache file of a key: <cacheDir>/<key>.vdb.
std::string cachePath(const std::string& cacheDir, const std::string& key);

}  // namespace rs
