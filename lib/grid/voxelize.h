// Scene → OcclusionGrid (docs/design.md §5, paper §4). Two voxelizers computing the same six
// occlusion counts per voxel by the same sub-sample rule:
//  - the GPU voxelizer: headless EGL/OpenGL 4.5, for each axis intervals of at most 64
//    slices rasterized with an orthographic camera at 4×4 supersampling, slice bits OR-ed
//    into integer attachments, front and back facing apart, then a reduction to counts;
//  - the CPU voxelizer: the reference for tests and the fallback (--voxelizer cpu).
// Sub-sample rule (both): for axis a, the voxel face perpendicular to a is split into 4×4
// sub-samples; sub-sample (u, v) of voxel column (i, j) is covered by a triangle when the
// sub-sample's centre lies inside the triangle's projection along a (GL fill rules), and
// the triangle's a-coordinate there falls in slice k → voxel (i, j, k), side + or − by the
// sign of the triangle's geometric normal along a. The count is the number of covered
// sub-samples (0…16).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/log.h"
#include "grid/occlusion_grid.h"
#include "core/parallel.h"
#include "scene/scene.h"

namespace rs {

// The GPU voxelizer's largest tile edge in pixels. A power of two; 4096 keeps every window
// coordinate's arithmetic exact in float (see glsl/voxelize.vert) and the readback of one tile
// (RGBA32UI) at 256 MiB.
constexpr int kMaxTilePixels = 4096;

using IVec2 = glm::ivec2;

enum class VoxelizerKind { Gpu, Cpu };

struct VoxelizeTimings {
    double setup = 0;  // EGL context and shader compilation, seconds
    double upload = 0, raster = 0, readback = 0, reduction = 0;  // seconds; raster includes glFinish
    int passes = 0;  // draws of all triangles (axis × interval × viewport tile)
    double total() const { return setup + upload + raster + readback + reduction; }
};

OcclusionGrid voxelizeCpu(const Scene& scene, const GridGeometry& grid, ThreadPool& pool, Reporter& reporter);

// Creates a headless EGL context on the calling thread (hardware device first, then Mesa's
// llvmpipe); throws Error(Gpu) with a one-line reason when there is no usable EGL.
OcclusionGrid voxelizeGpu(const Scene& scene, const GridGeometry& grid, Reporter& reporter,
                          VoxelizeTimings* timings = nullptr);

// -- Shared by both voxelizers (voxelize_cpu.cpp defines them) -------------------------

// Vertices are snapped to multiples of 1/kSnapPerVoxel voxel: at 4 sub-samples a voxel that
// is 1/256 of a pixel, the sub-pixel precision of GL rasterizers (Mesa's llvmpipe, NVIDIA,
// AMD), so the GPU's own snapping changes nothing and the CPU's integer edge functions see
// the same vertices. Sub-sample centres are at (p + 0.5)/4 voxel = multiples of 1/8 voxel.
constexpr int kSnapPerVoxel = 1024;
constexpr int kMaxSlicesPerPass = 64;  // bits of one RG (or BA) mask

// Triangles in voxel space for the voxelizers. For axis a with in-plane axes
// u = (a+1) mod 3, v = (a+2) mod 3, plane a of triangle t is planes[3t + a] =
// (c0, cu, cv, sign): the triangle's a-coordinate over the projection plane is
// c0 + cu·u + cv·v (evaluated as (c0 + cu·u) + cv·v in float, no fused multiply-add), and
// sign is that of the geometric normal's a-component (+1, −1, or 0 where the triangle is
// parallel to a and its projection has no area). slices[3t + a] = (floor of the lowest,
// floor of the highest vertex coordinate along a): the plane's slice is clamped to it, so
// float rounding on steep triangles never puts a hit outside the triangle's own extent, and
// the GPU can skip a triangle in the intervals it does not reach.
//
// Cut-out surfaces (alphaMode MASK or BLEND, docs/design.md §3) cover a sub-sample where their
// texel there is solid: cutout[t] indexes triangle t's cut-out data, or is kSolid. For axis a,
// cutoutPlanes[6c + 2a] and [6c + 2a + 1] give the texture's u and v over the projection plane
// as the planes give depth, (c0, cu, cv, 0), evaluated in the same float operations; the texel
// is (⌊fract(u)·W⌋, ⌊fract(v)·H⌋) of cutoutInfo[c] = (first level, W, H, 0), and its level
// (0…255: MASK 255 where factor × texel alpha ≥ cutoff, else 0; BLEND round(255·alpha)) is
// compared with a hash of the sub-sample, the axis and the triangle (cutoutHash): covered when
// hash mod 255 < level. Integer operations throughout, the same in glsl/voxelize.frag.
struct VoxelTriangles {
    static constexpr uint32_t kSolid = 0xffffffffu;
    std::vector<Vec3> positions;    // 3 per triangle, voxel space, snapped
    std::vector<Vec4> planes;       // 3 per triangle
    std::vector<IVec2> slices;      // 3 per triangle
    std::vector<uint32_t> cutout;       // per triangle
    std::vector<Vec4> cutoutPlanes;     // 6 per cut-out triangle
    std::vector<glm::uvec4> cutoutInfo; // per cut-out triangle
    std::vector<uint32_t> levels;       // texel levels of every cut-out material
    size_t count() const { return positions.size() / 3; }
};

inline uint32_t cutoutHash(uint32_t px, uint32_t py, uint32_t axis, uint32_t tri) {
    uint32_t h = px * 0x8da6b343u ^ py * 0xd8163841u ^ (tri * 3u + axis) * 0xcb1ab31fu;
    h ^= h >> 15;
    h *= 0x2c1b3c6du;
    h ^= h >> 12;
    h *= 0x297a2d39u;
    h ^= h >> 15;
    return h;
}

// Whether cut-out triangle c covers sub-sample (px, py) at voxel-space (uCoord, vCoord) of axis a.
inline bool cutoutCovers(const VoxelTriangles& tris, uint32_t c, uint32_t tri, int a, float uCoord, float vCoord,
                         uint32_t px, uint32_t py) {
    float tex[2];
    for (int k = 0; k < 2; ++k) {
        const Vec4 p = tris.cutoutPlanes[6 * c + 2 * a + k];
        float t = p.y * uCoord;  // the order of glsl/voxelize.frag, no fused multiply-add
        float s = p.x + t;
        float r = p.z * vCoord;
        tex[k] = s + r;
    }
    const glm::uvec4 info = tris.cutoutInfo[c];
    const float fx = tex[0] - std::floor(tex[0]), fy = tex[1] - std::floor(tex[1]);
    const uint32_t x = std::min(uint32_t(fx * float(info.y)), info.y - 1u);
    const uint32_t y = std::min(uint32_t(fy * float(info.z)), info.z - 1u);
    return cutoutHash(px, py, uint32_t(a), tri) % 255u < tris.levels[info.x + y * info.y + x];
}
VoxelTriangles prepareVoxelTriangles(const Scene& scene, const GridGeometry& grid);

// Throws Error(Config) with a memory estimate when the grid's OcclusionGrid would exceed
// kMaxGridBytes.
constexpr double kMaxGridBytes = 16.0 * (1ull << 30);
void checkGridSize(const GridGeometry& grid);

}  // namespace rs
