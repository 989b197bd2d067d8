// CPU voxelizer: the reference for tests and the fallback `--voxelizer cpu` (docs/design.md §5).
// Takes the Scene (world space) and a GridGeometry, returns the OcclusionGrid: for each
// axis a and each voxel, how many of the voxel face's 4×4 sub-samples are covered by
// triangles facing +a and −a (see voxelize.h for the sub-sample rule).
//
// It applies the GPU's rule exactly: vertices snapped to 1/256 pixel (prepareVoxelTriangles),
// coverage of each sub-sample centre by integer edge functions with the fill convention of
// GL rasterizers for framebuffer objects (a centre exactly on an edge belongs to the
// triangle to its right and above; measured against llvmpipe in voxelize_test), the slice
// from the same float plane evaluation as glsl/voxelize.frag, and OR (not sum) of triangles
// that cover the same sub-sample in the same voxel. Work is split into rows of voxel
// columns; each row owns its voxels, so the result does not depend on the thread count.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "grid/voxelize.h"

namespace rs {

void checkGridSize(const GridGeometry& grid) {
    double bytes = double(grid.voxelCount()) * kSideCount;
    if (bytes > kMaxGridBytes) {
        char buf[200];
        std::snprintf(buf, sizeof buf,
                      "a %dx%dx%d grid needs %.1f GiB for its occlusion counts (limit %.0f GiB): use a smaller `grid`",
                      grid.dims.x, grid.dims.y, grid.dims.z, bytes / double(1ull << 30),
                      kMaxGridBytes / double(1ull << 30));
        throw Error(ErrorKind::Config, buf);
    }
}

namespace {

// The texel levels of cut-out material m (VoxelTriangles): one per texel of its base colour
// texture, or one for the whole surface without a texture alpha.
std::vector<uint32_t> cutoutLevels(const Scene& scene, uint32_t m, int& width, int& height) {
    const Material& mat = scene.materials[m];
    const Texture* tex = mat.baseColorTexture.present() ? &scene.textures[size_t(mat.baseColorTexture.texture)] : nullptr;
    if (tex && !tex->hasAlpha()) tex = nullptr;
    width = tex ? tex->width() : 1;
    height = tex ? tex->height() : 1;
    std::vector<uint32_t> levels(size_t(width) * height);
    for (size_t i = 0; i < levels.size(); ++i) {
        const float alpha = mat.opacity * (tex ? tex->alphaAt(int(i)) : 1.f);
        levels[i] = mat.alphaMode == AlphaMode::Mask ? (alpha >= mat.alphaCutoff ? 255u : 0u)
                                                     : uint32_t(std::lround(std::clamp(alpha, 0.f, 1.f) * 255.f));
    }
    return levels;
}

// The cut-out data of VoxelTriangles: texture planes from the snapped positions and the uvs.
void prepareCutouts(const Scene& scene, VoxelTriangles& out) {
    const size_t n = scene.triangleCount();
    out.cutout.assign(n, VoxelTriangles::kSolid);
    std::vector<glm::uvec4> infoOfMaterial(scene.materials.size(), glm::uvec4(0));
    for (uint32_t m = 0; m < scene.materials.size(); ++m) {
        if (scene.materials[m].alphaMode == AlphaMode::Opaque) continue;
        int w, h;
        const std::vector<uint32_t> levels = cutoutLevels(scene, m, w, h);
        infoOfMaterial[m] = glm::uvec4(uint32_t(out.levels.size()), uint32_t(w), uint32_t(h), 0u);
        out.levels.insert(out.levels.end(), levels.begin(), levels.end());
    }
    for (size_t t = 0; t < n; ++t) {
        const uint32_t m = scene.triMaterial[t];
        if (scene.materials[m].alphaMode == AlphaMode::Opaque) continue;
        out.cutout[t] = uint32_t(out.cutoutInfo.size());
        out.cutoutInfo.push_back(infoOfMaterial[m]);
        DVec3 p[3];
        for (int i = 0; i < 3; ++i) p[i] = DVec3(out.positions[3 * t + i]);
        for (int a = 0; a < 3; ++a) {
            const int u = (a + 1) % 3, v = (a + 2) % 3;
            // Solve c0 + cu·p[i][u] + cv·p[i][v] = uv_i for the three vertices (Cramer's rule).
            const double det = (p[1][u] - p[0][u]) * (p[2][v] - p[0][v]) - (p[2][u] - p[0][u]) * (p[1][v] - p[0][v]);
            for (int k = 0; k < 2; ++k) {
                if (det == 0.0) {
                    out.cutoutPlanes.push_back(Vec4(0.f));
                    continue;
                }
                const TextureRef& ref = scene.materials[m].baseColorTexture;
                const double f0 = scene.cornerTextureUv(ref, t, 0)[k], f1 = scene.cornerTextureUv(ref, t, 1)[k],
                             f2 = scene.cornerTextureUv(ref, t, 2)[k];
                const double cu = ((f1 - f0) * (p[2][v] - p[0][v]) - (f2 - f0) * (p[1][v] - p[0][v])) / det;
                const double cv = ((p[1][u] - p[0][u]) * (f2 - f0) - (p[2][u] - p[0][u]) * (f1 - f0)) / det;
                const double c0 = f0 - cu * p[0][u] - cv * p[0][v];
                out.cutoutPlanes.push_back(Vec4(float(c0), float(cu), float(cv), 0.f));
            }
        }
    }
}

}  // namespace

VoxelTriangles prepareVoxelTriangles(const Scene& scene, const GridGeometry& grid) {
    VoxelTriangles out;
    size_t n = scene.triangleCount();
    out.positions.resize(3 * n);
    out.planes.resize(3 * n);
    out.slices.resize(3 * n);
    const DVec3 origin(grid.origin);
    const double invVoxel = 1.0 / double(grid.voxelSize);
    for (size_t t = 0; t < n; ++t) {
        DVec3 p[3];
        for (int i = 0; i < 3; ++i) {
            DVec3 pVoxel = (DVec3(scene.positions[3 * t + i]) - origin) * invVoxel;
            p[i] = glm::round(pVoxel * double(kSnapPerVoxel)) / double(kSnapPerVoxel);
            out.positions[3 * t + i] = Vec3(p[i]);
        }
        // Exact in double: coordinates have at most 23 significant bits.
        DVec3 normal = glm::cross(p[1] - p[0], p[2] - p[0]);
        for (int a = 0; a < 3; ++a) {
            int u = (a + 1) % 3, v = (a + 2) % 3;
            out.slices[3 * t + a] = IVec2(int(std::floor(std::min({p[0][a], p[1][a], p[2][a]}))),
                                          int(std::floor(std::max({p[0][a], p[1][a], p[2][a]}))));
            if (normal[a] == 0) {
                out.planes[3 * t + a] = Vec4(0.f);
                continue;
            }
            double cu = -normal[u] / normal[a], cv = -normal[v] / normal[a];
            double c0 = p[0][a] - cu * p[0][u] - cv * p[0][v];
            out.planes[3 * t + a] = Vec4(float(c0), float(cu), float(cv), normal[a] > 0 ? 1.f : -1.f);
        }
    }
    prepareCutouts(scene, out);
    return out;
}

namespace {

struct FixedTriangle {
    int64_t x[3], y[3];  // 1/256 pixel, counter-clockwise in (u, v)
    int64_t bias[3];     // 1 where a centre exactly on edge i counts as inside
};

// Counter-clockwise in (u, v) with v up; false for a projection without area.
bool setupTriangle(const Vec3* p, int u, int v, FixedTriangle& f) {
    for (int i = 0; i < 3; ++i) {
        f.x[i] = int64_t(std::llround(double(p[i][u]) * kSnapPerVoxel));
        f.y[i] = int64_t(std::llround(double(p[i][v]) * kSnapPerVoxel));
    }
    int64_t area2 = (f.x[1] - f.x[0]) * (f.y[2] - f.y[0]) - (f.y[1] - f.y[0]) * (f.x[2] - f.x[0]);
    if (area2 == 0) return false;
    if (area2 < 0) {
        std::swap(f.x[1], f.x[2]);
        std::swap(f.y[1], f.y[2]);
    }
    for (int i = 0; i < 3; ++i) {
        int j = (i + 1) % 3;
        int64_t dx = f.x[j] - f.x[i], dy = f.y[j] - f.y[i];
        // Fill convention for GL framebuffer objects (window y up, row 0 first in memory):
        // left edges (going down in a counter-clockwise triangle) and bottom edges
        // (horizontal, going right) own the centres on them.
        f.bias[i] = (dy < 0 || (dy == 0 && dx > 0)) ? 1 : 0;
    }
    return true;
}

// Sub-sample centre of pixel p along one in-plane axis, in 1/256 pixel.
inline int64_t centreFixed(int64_t pixel) { return pixel * 256 + 128; }

// First and last pixel whose centre lies in [lo, hi] (1/256 pixel), clamped to [0, n).
inline void pixelRange(int64_t lo, int64_t hi, int64_t n, int64_t& first, int64_t& last) {
    auto floorDiv = [](int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); };
    first = std::max<int64_t>(0, floorDiv(lo - 128 + 255, 256));
    last = std::min<int64_t>(n - 1, floorDiv(hi - 128, 256));
}

struct AxisJob {
    int a, u, v;
    IVec3 dims;
    int words;  // 64-bit words per sub-sample mask along a
    std::vector<uint32_t> rowStart, rowTris;  // triangles per voxel row (CSR)
};

// Rasterizes the triangles of voxel row j (4 pixel rows) into per-sub-sample slice masks,
// then adds the bits to the grid's counts of that row's voxels.
void voxelizeRow(const VoxelTriangles& tris, const AxisJob& job, int j, std::vector<uint64_t>& masks,
                 OcclusionGrid& grid) {
    const int64_t width = int64_t(job.dims[job.u]) * kSubsamplesPerAxis;
    const size_t perSign = size_t(kSubsamplesPerAxis) * width * job.words;
    masks.assign(2 * perSign, 0);
    const int64_t py0 = int64_t(j) * kSubsamplesPerAxis;
    for (uint32_t k = job.rowStart[j]; k < job.rowStart[j + 1]; ++k) {
        uint32_t t = job.rowTris[k];
        FixedTriangle f;
        if (!setupTriangle(&tris.positions[3 * t], job.u, job.v, f)) continue;
        const Vec4 plane = tris.planes[3 * t + job.a];
        const Vec2 range(tris.slices[3 * t + job.a]);
        uint64_t* mask = masks.data() + (plane.w > 0 ? 0 : perSign);
        int64_t xFirst, xLast, yFirst, yLast;
        pixelRange(std::min({f.x[0], f.x[1], f.x[2]}), std::max({f.x[0], f.x[1], f.x[2]}), width, xFirst, xLast);
        pixelRange(std::min({f.y[0], f.y[1], f.y[2]}), std::max({f.y[0], f.y[1], f.y[2]}), py0 + kSubsamplesPerAxis,
                   yFirst, yLast);
        yFirst = std::max(yFirst, py0);
        for (int64_t py = yFirst; py <= yLast; ++py) {
            const int64_t cy = centreFixed(py);
            const float vCoord = (float(py) + 0.5f) * 0.25f;
            int64_t e[3], step[3];
            for (int i = 0; i < 3; ++i) {
                int i1 = (i + 1) % 3;
                int64_t dx = f.x[i1] - f.x[i], dy = f.y[i1] - f.y[i];
                // E(P) = dx·(Py − yi) − dy·(Px − xi) > 0 inside a counter-clockwise triangle.
                e[i] = dx * (cy - f.y[i]) - dy * (centreFixed(xFirst) - f.x[i]) + f.bias[i] - 1;
                step[i] = -dy * 256;
            }
            for (int64_t px = xFirst; px <= xLast; ++px) {
                if (e[0] >= 0 && e[1] >= 0 && e[2] >= 0) {
                    // Same operations, same order as glsl/voxelize.frag.
                    const float uCoord = (float(px) + 0.5f) * 0.25f;
                    float tu = plane.y * uCoord;
                    float s = plane.x + tu;
                    float r = plane.z * vCoord;
                    float depth = s + r;
                    float slice = std::min(std::max(std::floor(depth), range.x), range.y);
                    const uint32_t c = tris.cutout[t];
                    if (slice >= 0.f && slice < float(job.dims[job.a]) &&
                        (c == VoxelTriangles::kSolid ||
                         cutoutCovers(tris, c, t, job.a, uCoord, vCoord, uint32_t(px), uint32_t(py)))) {
                        int bit = int(slice);
                        mask[(size_t((py - py0) * width + px)) * job.words + bit / 64] |= uint64_t(1) << (bit % 64);
                    }
                }
                e[0] += step[0];
                e[1] += step[1];
                e[2] += step[2];
            }
        }
    }
    // Reduction: each set bit is one covered sub-sample of voxel (k along a, i, j).
    for (int sign = 0; sign < 2; ++sign) {
        const uint64_t* mask = masks.data() + sign * perSign;
        const int side = 2 * job.a + sign;
        for (int64_t row = 0; row < kSubsamplesPerAxis; ++row)
            for (int64_t px = 0; px < width; ++px)
                for (int w = 0; w < job.words; ++w)
                    for (uint64_t bits = mask[size_t(row * width + px) * job.words + w]; bits; bits &= bits - 1) {
                        IVec3 c;
                        c[job.a] = w * 64 + __builtin_ctzll(bits);
                        c[job.u] = int(px / kSubsamplesPerAxis);
                        c[job.v] = j;
                        grid.counts[grid.geometry.index(c.x, c.y, c.z) * kSideCount + side]++;
                    }
    }
}

}  // namespace

OcclusionGrid voxelizeCpu(const Scene& scene, const GridGeometry& geometry, ThreadPool& pool, Reporter& reporter) {
    checkGridSize(geometry);
    OcclusionGrid grid(geometry);
    const VoxelTriangles tris = prepareVoxelTriangles(scene, geometry);
    const IVec3 dims = geometry.dims;
    reporter.begin("voxelizing (cpu)", int64_t(dims.x) + dims.y + dims.z, "rows");
    std::vector<std::vector<uint64_t>> scratch(size_t(pool.size()));
    for (int a = 0; a < 3; ++a) {
        AxisJob job{a, (a + 1) % 3, (a + 2) % 3, dims, (dims[a] + 63) / 64, {}, {}};
        const int rows = dims[job.v];
        // Bin triangles into the voxel rows (along v) their projection may touch.
        auto rowRange = [&](size_t t, int64_t& first, int64_t& last) {
            float lo = kInf, hi = -kInf;
            for (int i = 0; i < 3; ++i) {
                lo = std::min(lo, tris.positions[3 * t + i][job.v]);
                hi = std::max(hi, tris.positions[3 * t + i][job.v]);
            }
            first = std::max<int64_t>(0, int64_t(std::floor(lo)));
            last = std::min<int64_t>(rows - 1, int64_t(std::floor(hi)));
        };
        job.rowStart.assign(size_t(rows) + 1, 0);
        for (size_t t = 0; t < tris.count(); ++t) {
            if (tris.planes[3 * t + a].w == 0) continue;
            int64_t first, last;
            rowRange(t, first, last);
            for (int64_t j = first; j <= last; ++j) job.rowStart[j + 1]++;
        }
        for (int j = 0; j < rows; ++j) job.rowStart[j + 1] += job.rowStart[j];
        job.rowTris.resize(job.rowStart[rows]);
        std::vector<uint32_t> fill(job.rowStart.begin(), job.rowStart.end() - 1);
        for (size_t t = 0; t < tris.count(); ++t) {
            if (tris.planes[3 * t + a].w == 0) continue;
            int64_t first, last;
            rowRange(t, first, last);
            for (int64_t j = first; j <= last; ++j) job.rowTris[fill[j]++] = uint32_t(t);
        }
        pool.parallelFor(rows, 1, [&](int64_t begin, int64_t end, int thread) {
            for (int64_t j = begin; j < end; ++j) voxelizeRow(tris, job, int(j), scratch[size_t(thread)], grid);
            reporter.advance(end - begin);
        });
    }
    reporter.end();
    return grid;
}

}  // namespace rs
