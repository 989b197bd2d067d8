// OcclusionGrid ⇄ OpenVDB file (docs/design.md §5): for inspection in Blender and as the voxel cache.
//
// A file holds eight grids, all with the same sparse topology (the occupied voxels only):
//   density   FloatGrid, class fog volume: max of the six occlusion ratios, so Blender shows
//             the voxelized scene as a volume;
//   normal    Vec3SGrid: the voxel's mean normal (paper Fig. 3) normalised, (0,0,0) where the
//             six counts cancel (vec3s, not vec3d: Blender 5 aborts on vec3d);
//   occ_px, occ_nx, occ_py, occ_ny, occ_pz, occ_nz
//             FloatGrid: count/16 of each side (exact in float, so counts round-trip).
//
// Spaces. Voxel (i, j, k) of the OcclusionGrid covers [i, i+1)³ of voxel space and
// glTF world = geometry.origin + pVoxel · voxelSize (+Y up). The file's transform maps the
// VDB index (i, j, k) (a cell-centred value) to that voxel's centre in *Blender's* world,
// which is glTF world turned +Y-up → +Z-up the way Blender's glTF importer does it:
//   blenderFromGltf(x, y, z) = (x, −z, y),
//   pBlender(i, j, k) = blenderFromGltf(origin + ((i, j, k) + 0.5) · voxelSize),
// so the .vdb overlays the glTF when both are imported into Blender. Reading inverts this
// and checks it against the raw GridGeometry kept in the file metadata.
//
// File metadata (keys "raysplat_*"): format version, generator, cache key, voxelizer,
// supersampling, dims, voxel size, origin, grid bounds (glTF world), scene path and bounds,
// occupied voxel count. Writes are atomic (temporary name + rename).
//
// This header does not include OpenVDB (docs/design.md §1): only vdb_io.cpp does.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "grid/occlusion_grid.h"
#include "grid/voxelize.h"

namespace rs {

// Bumped whenever the file layout or the meaning of a grid changes; part of the cache key.
constexpr int kVdbFormatVersion = 1;
// Sub-samples per voxel face along each in-plane axis (4×4), recorded and part of the key.
constexpr int kVoxelizerSupersampling = 4;

struct VdbMetadata {
    std::string cacheKey;       // 16 hex digits, see cacheKey()
    std::string voxelizer;      // "gpu" or "cpu": which voxelizer computed the counts
    int supersampling = kVoxelizerSupersampling;
    int formatVersion = kVdbFormatVersion;
    std::string generator;      // "raysplat 0.1.0"; filled by writeVdb when empty
    std::string scene;          // the scene file it was made from (informational)
    Bounds3 sceneBounds;        // glTF world (informational)
};

struct VdbFile {
    OcclusionGrid grid;
    VdbMetadata metadata;
};

// Writes the grid and metadata to `path` atomically; throws Error(Io) naming the file.
void writeVdb(const std::string& path, const OcclusionGrid& grid, const VdbMetadata& metadata);
// The same, written to `file` as is (a staged temporary of `path`; errors name `path`).
void writeVdbTo(const std::string& file, const std::string& path, const OcclusionGrid& grid,
                const VdbMetadata& metadata);

// Reads a file written by writeVdb. Throws Error(Io) with a one-line message naming the file
// when it is missing, truncated, corrupt, of another format version, or not a raysplat grid.
// OpenVDB trusts the lengths in the file: a corrupt one can ask for an absurd allocation
// (std::bad_alloc, reported as a corrupt file).
VdbFile readVdb(const std::string& path);

// The voxel cache's files: a VDB followed by a 16-byte trailer ("RSVDBSUM" and a 64-bit
// FNV-1a hash of every byte before it; OpenVDB ignores what follows its grids, so the file
// still opens in Blender). readCacheVdb checks the trailer before OpenVDB reads a byte, so a
// truncated or corrupted cache file is a clean Error, never OpenVDB parsing garbage.
void writeCacheVdb(const std::string& path, const OcclusionGrid& grid, const VdbMetadata& metadata);
VdbFile readCacheVdb(const std::string& path);

// The cache key: a 64-bit hash (16 hex digits) over the triangle positions' bit patterns,
// the grid resolution, the voxelizer kind and supersampling, and kVdbFormatVersion. Any
// change of geometry or voxelizer settings gives another key. Defined in vdb_key.cpp.
std::string cacheKey(const Scene& scene, int resolution, VoxelizerKind kind);
const char* voxelizerName(VoxelizerKind kind);  // "gpu" / "cpu"

// What a .vdb file holds, grid by grid, as OpenVDB read it: for tests and debugging.
struct VdbGridDump {
    std::string name;
    std::string valueType;  // OpenVDB's type name: "float", "vec3s", …
    std::string gridClass;  // "fog volume", "level set", "unknown"
    // pWorld = worldFromIndex · (i, j, k, 1), row-major, from the file's own transform.
    double worldFromIndex[4][4];
    std::vector<IVec3> coords;  // active voxels (tiles expanded), in iteration order
    std::vector<Vec3> values;   // (value, 0, 0) for scalar grids
};
std::vector<VdbGridDump> dumpVdb(const std::string& path);

}  // namespace rs
