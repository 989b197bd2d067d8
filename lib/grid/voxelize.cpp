// GPU voxelizer (docs/design.md §5, paper §4): Scene + GridGeometry → OcclusionGrid through a
// headless OpenGL 4.5 context. Triangles are uploaded once in voxel space (snapped, see
// voxelize.h) with their three plane equations in a storage buffer. For each axis a, the
// slices along a are cut into intervals of at most 64; each interval is one draw of the
// triangles that reach it (an index list per interval: the same result as drawing all, for
// a fraction of llvmpipe's triangle setup) with an orthographic camera looking along a (culling and depth test off) into
// an RGBA32UI attachment at 4×4 supersampling, where glsl/voxelize.frag ORs the
// sub-sample's slice bit into RG (normal along +a) or BA (along −a). The attachment is read
// back and each set bit adds one covered sub-sample to that voxel side's count.
// Images larger than 4096 pixels (or the driver's texture limit) are cut into tiles.
//
// Nothing is clipped, so the GPU rasterizes exactly the snapped triangles that
// voxelize_cpu.cpp does and the two agree bit for bit (voxelize_test): depth clamp turns
// off near/far clipping (the shader discards slices outside the interval instead; clipping
// made new, unsnapped vertices that moved ~1e-5 of the voxel sides by one sub-sample), and
// the viewport spans the whole image, a tile being selected by the viewport's offset and
// the attachment's size. Only an image beyond GL_MAX_VIEWPORT_DIMS falls back to a
// viewport per tile, where triangles crossing the tile's guard band may be clipped.
#include "grid/voxelize.h"

#include "core/error.h"

#ifdef RAYSPLAT_HAVE_EGL

#include <algorithm>

#define GL_GLEXT_PROTOTYPES
#include <GL/glcorearb.h>

#include "grid/gpu_context.h"
#include "grid/shaders.h"
#include "core/stats.h"
#include "core/stop.h"

namespace rs {

namespace {

int floorPowerOfTwo(int x) {
    int p = 1;
    while (p * 2 <= x) p *= 2;
    return p;
}
int ceilPowerOfTwo(int x) {
    int p = 1;
    while (p < x) p *= 2;
    return p;
}

struct GlObjects {
    GLuint vao = 0, vertices = 0, planes = 0, slices = 0, indices = 0, texture = 0, framebuffer = 0;
    GLuint cutout[4] = {0, 0, 0, 0};  // cutout, cutoutPlanes, cutoutInfo, levels: bindings 2–5
    ~GlObjects() {
        glDeleteBuffers(4, cutout);
        glDeleteFramebuffers(1, &framebuffer);
        glDeleteTextures(1, &texture);
        glDeleteBuffers(1, &indices);
        glDeleteBuffers(1, &slices);
        glDeleteBuffers(1, &planes);
        glDeleteBuffers(1, &vertices);
        glDeleteVertexArrays(1, &vao);
    }
};

struct Pass {
    int axis, sliceStart, sliceCount;
    IVec3 tileVoxel;  // first voxel column of the tile: (u, v) in .x, .y
    int tileWidth, tileHeight;  // in pixels
};

// Adds the read-back masks of one pass to the counts: pixel (x, y) is sub-sample
// (x mod 4, y mod 4) of voxel column (u0 + x/4, v0 + y/4).
void reducePass(const Pass& pass, const std::vector<uint32_t>& pixels, OcclusionGrid& grid) {
    const int a = pass.axis, u = (a + 1) % 3, v = (a + 2) % 3;
    for (int y = 0; y < pass.tileHeight; ++y) {
        for (int x = 0; x < pass.tileWidth; ++x) {
            const uint32_t* p = &pixels[(size_t(y) * pass.tileWidth + x) * 4];
            if (!(p[0] | p[1] | p[2] | p[3])) continue;
            IVec3 c;
            c[u] = pass.tileVoxel.x + x / kSubsamplesPerAxis;
            c[v] = pass.tileVoxel.y + y / kSubsamplesPerAxis;
            for (int sign = 0; sign < 2; ++sign) {
                uint64_t bits = uint64_t(p[2 * sign]) | uint64_t(p[2 * sign + 1]) << 32;
                for (; bits; bits &= bits - 1) {
                    c[a] = pass.sliceStart + __builtin_ctzll(bits);
                    grid.counts[grid.geometry.index(c.x, c.y, c.z) * kSideCount + 2 * a + sign]++;
                }
            }
        }
    }
}

// -- Planning: the triangles' index lists, the driver's limits, the passes ------------------

// For each axis and interval of kMaxSlicesPerPass slices, the triangles whose slice range meets
// it, in triangle order (so that a batch of triangles is a contiguous part of each list), as
// one index array: list (axis a, interval i) is [start[a][i], start[a][i + 1]).
struct TriangleLists {
    std::vector<uint32_t> indices;
    std::vector<std::vector<size_t>> start{3};
};

TriangleLists listTriangles(const VoxelTriangles& tris, const IVec3& dims) {
    TriangleLists out;
    for (int a = 0; a < 3; ++a) {
        const int intervals = (dims[a] + kMaxSlicesPerPass - 1) / kMaxSlicesPerPass;
        std::vector<std::vector<uint32_t>> lists(static_cast<size_t>(intervals));
        for (size_t t = 0; t < tris.count(); ++t) {
            if (tris.planes[3 * t + a].w == 0) continue;  // parallel to a: no projected area
            const IVec2 r = tris.slices[3 * t + a];
            const int first = std::max(r.x, 0) / kMaxSlicesPerPass;
            const int last = std::min(r.y, dims[a] - 1) / kMaxSlicesPerPass;
            for (int i = first; i <= last && r.y >= 0; ++i)
                for (uint32_t k = 0; k < 3; ++k) lists[size_t(i)].push_back(uint32_t(3 * t) + k);
        }
        for (const auto& list : lists) {
            out.start[size_t(a)].push_back(out.indices.size());
            out.indices.insert(out.indices.end(), list.begin(), list.end());
        }
        out.start[size_t(a)].push_back(out.indices.size());
    }
    return out;
}

// Vertices, planes, slice ranges and index lists into GL buffers, bound to one VAO.
void uploadTriangles(const VoxelTriangles& tris, const TriangleLists& lists, GlObjects& gl) {
    glCreateVertexArrays(1, &gl.vao);
    glCreateBuffers(1, &gl.vertices);
    glCreateBuffers(1, &gl.planes);
    glCreateBuffers(1, &gl.slices);
    glCreateBuffers(1, &gl.indices);
    if (tris.count()) {
        glNamedBufferStorage(gl.vertices, GLsizeiptr(tris.positions.size() * sizeof(Vec3)), tris.positions.data(), 0);
        glNamedBufferStorage(gl.planes, GLsizeiptr(tris.planes.size() * sizeof(Vec4)), tris.planes.data(), 0);
        glNamedBufferStorage(gl.slices, GLsizeiptr(tris.slices.size() * sizeof(IVec2)), tris.slices.data(), 0);
    }
    if (!lists.indices.empty())
        glNamedBufferStorage(gl.indices, GLsizeiptr(lists.indices.size() * sizeof(uint32_t)), lists.indices.data(), 0);
    // The cut-out buffers, each at least one word (a storage block may not be empty).
    glCreateBuffers(4, gl.cutout);
    const uint32_t none = 0;
    auto store = [&](GLuint buffer, const void* data, size_t bytes) {
        glNamedBufferStorage(buffer, GLsizeiptr(bytes ? bytes : sizeof none), bytes ? data : &none, 0);
    };
    store(gl.cutout[0], tris.cutout.data(), tris.cutout.size() * sizeof(uint32_t));
    store(gl.cutout[1], tris.cutoutPlanes.data(), tris.cutoutPlanes.size() * sizeof(Vec4));
    store(gl.cutout[2], tris.cutoutInfo.data(), tris.cutoutInfo.size() * sizeof(glm::uvec4));
    store(gl.cutout[3], tris.levels.data(), tris.levels.size() * sizeof(uint32_t));
    for (int b = 0; b < 4; ++b) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GLuint(2 + b), gl.cutout[b]);
    glVertexArrayElementBuffer(gl.vao, gl.indices);
    glVertexArrayVertexBuffer(gl.vao, 0, gl.vertices, 0, sizeof(Vec3));
    glVertexArrayAttribFormat(gl.vao, 0, 3, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(gl.vao, 0, 0);
    glEnableVertexArrayAttrib(gl.vao, 0);
}

struct DriverLimits {
    GLint viewportBounds[2] = {0, 0}, maxViewport[2] = {0, 0}, maxTexture = 0;
    size_t batch = 1;  // triangles a draw: the storage blocks of one batch fit the driver's limit

    DriverLimits() {
        GLint maxBlock = 0, blockAlign = 1;
        glGetIntegerv(GL_VIEWPORT_BOUNDS_RANGE, viewportBounds);
        glGetIntegerv(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &maxBlock);
        glGetIntegerv(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT, &blockAlign);
        glGetIntegerv(GL_MAX_TEXTURE_SIZE, &maxTexture);
        glGetIntegerv(GL_MAX_VIEWPORT_DIMS, maxViewport);
        // A storage block may be smaller than the scene's planes (the GL minimum is 128 MiB,
        // 2.8 M triangles): draw in batches whose offsets meet the binding alignment.
        const size_t bytesPerTri = 3 * sizeof(Vec4);  // the larger of the two storage buffers
        batch = std::max<size_t>(1, size_t(std::max(maxBlock, 1 << 20)) / bytesPerTri);
        batch -= batch % size_t(std::max(blockAlign, 1));  // batch·48 is then a multiple of the alignment
        batch = std::max<size_t>(batch, size_t(std::max(blockAlign, 1)));
    }
};

// One pass per (axis, interval, tile): the viewport is 4× the grid's in-plane dims, cut into
// tiles where the driver requires. texSize: the largest tile, the attachment's size.
std::vector<Pass> planPasses(const IVec3& dims, const DriverLimits& limits, IVec2& texSize) {
    const int tilePixels = floorPowerOfTwo(
        std::min({kMaxTilePixels, int(limits.maxTexture), int(limits.maxViewport[0]), int(limits.maxViewport[1])}));
    if (tilePixels < kSubsamplesPerAxis)
        throw Error(ErrorKind::Gpu, "the GL driver's viewport or texture limit is below 4 pixels");
    const int tileVoxels = tilePixels / kSubsamplesPerAxis;
    std::vector<Pass> passes;
    texSize = IVec2(0);
    for (int a = 0; a < 3; ++a) {
        const int u = (a + 1) % 3, v = (a + 2) % 3;
        for (int s = 0; s < dims[a]; s += kMaxSlicesPerPass)
            for (int tv = 0; tv < dims[v]; tv += tileVoxels)
                for (int tu = 0; tu < dims[u]; tu += tileVoxels) {
                    Pass p{a, s, std::min(kMaxSlicesPerPass, dims[a] - s), IVec3(tu, tv, 0),
                           std::min(tileVoxels, dims[u] - tu) * kSubsamplesPerAxis,
                           std::min(tileVoxels, dims[v] - tv) * kSubsamplesPerAxis};
                    texSize = glm::max(texSize, IVec2(p.tileWidth, p.tileHeight));
                    passes.push_back(p);
                }
    }
    return passes;
}

// -- Passes: the attachment, the fixed state, one draw per pass ------------------------------

// An RGBA32UI attachment of texSize, bound, and the state every pass shares: every fragment
// counts, OR accumulates the slice bits.
void setUpTarget(GlObjects& gl, const GlProgram& program, IVec2 texSize) {
    glCreateTextures(GL_TEXTURE_2D, 1, &gl.texture);
    glTextureStorage2D(gl.texture, 1, GL_RGBA32UI, texSize.x, texSize.y);
    glCreateFramebuffers(1, &gl.framebuffer);
    glNamedFramebufferTexture(gl.framebuffer, GL_COLOR_ATTACHMENT0, gl.texture, 0);
    if (glCheckNamedFramebufferStatus(gl.framebuffer, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw Error(ErrorKind::Gpu, "the voxelizer's RGBA32UI framebuffer is incomplete");
    glBindFramebuffer(GL_FRAMEBUFFER, gl.framebuffer);
    glUseProgram(program.id());
    glBindVertexArray(gl.vao);
    glDisable(GL_CULL_FACE);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_MULTISAMPLE);
    glEnable(GL_DEPTH_CLAMP);
    glEnable(GL_COLOR_LOGIC_OP);
    glLogicOp(GL_OR);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
}

struct PassUniforms {
    GLint axis, tileOrigin, pixelOffset, viewportSize, depthRange, intervalStart, sliceCount, firstTriangle;
    explicit PassUniforms(const GlProgram& p)
        : axis(p.uniform("uAxis")), tileOrigin(p.uniform("uTileOrigin")), pixelOffset(p.uniform("uPixelOffset")),
          viewportSize(p.uniform("uViewportSize")), depthRange(p.uniform("uDepthRange")),
          intervalStart(p.uniform("uIntervalStart")), sliceCount(p.uniform("uSliceCount")),
          firstTriangle(p.uniform("uFirstTriangle")) {}
};

// Rasterizes one pass into the cleared attachment: the viewport spans the whole image, offset
// so that the tile lands on the attachment (or the tile alone where the driver cannot), and
// the pass's triangles are drawn batch by batch.
void drawPass(const Pass& pass, const IVec3& dims, const DriverLimits& limits, const PassUniforms& u,
              const TriangleLists& lists, size_t triCount, const GlObjects& gl) {
    const int tileX = pass.tileVoxel.x * kSubsamplesPerAxis, tileY = pass.tileVoxel.y * kSubsamplesPerAxis;
    int viewportW = ceilPowerOfTwo(dims[(pass.axis + 1) % 3] * kSubsamplesPerAxis);
    int viewportH = ceilPowerOfTwo(dims[(pass.axis + 2) % 3] * kSubsamplesPerAxis);
    const bool whole = viewportW <= limits.maxViewport[0] && viewportH <= limits.maxViewport[1] &&
                       -std::max(tileX, tileY) >= limits.viewportBounds[0];
    if (!whole) {
        viewportW = ceilPowerOfTwo(pass.tileWidth);
        viewportH = ceilPowerOfTwo(pass.tileHeight);
    }
    glViewport(whole ? -tileX : 0, whole ? -tileY : 0, viewportW, viewportH);
    glUniform2f(u.pixelOffset, whole ? 0.f : float(tileX), whole ? 0.f : float(tileY));
    glUniform1i(u.axis, pass.axis);
    glUniform2f(u.tileOrigin, float(tileX), float(tileY));
    glUniform2f(u.viewportSize, float(viewportW), float(viewportH));
    glUniform2f(u.depthRange, float(pass.sliceStart), float(pass.sliceStart + pass.sliceCount));
    glUniform1i(u.intervalStart, pass.sliceStart);
    glUniform1i(u.sliceCount, pass.sliceCount);
    const GLuint zero[4] = {0, 0, 0, 0};
    glClearBufferuiv(GL_COLOR, 0, zero);
    const size_t interval = size_t(pass.sliceStart / kMaxSlicesPerPass);
    const uint32_t* listBegin = lists.indices.data() + lists.start[size_t(pass.axis)][interval];
    const uint32_t* listEnd = lists.indices.data() + lists.start[size_t(pass.axis)][interval + 1];
    for (size_t first = 0; first < triCount && listBegin != listEnd; first += limits.batch) {
        const size_t count = std::min(limits.batch, triCount - first);
        const uint32_t* from = std::lower_bound(listBegin, listEnd, uint32_t(3 * first));
        const uint32_t* to = std::lower_bound(from, listEnd, uint32_t(3 * (first + count)));
        if (from == to) continue;
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 0, gl.planes, GLintptr(first * 3 * sizeof(Vec4)),
                          GLsizeiptr(count * 3 * sizeof(Vec4)));
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 1, gl.slices, GLintptr(first * 3 * sizeof(IVec2)),
                          GLsizeiptr(count * 3 * sizeof(IVec2)));
        glUniform1ui(u.firstTriangle, GLuint(first));
        glDrawElements(GL_TRIANGLES, GLsizei(to - from), GL_UNSIGNED_INT,
                       reinterpret_cast<const void*>((from - lists.indices.data()) * sizeof(uint32_t)));
    }
    glFinish();
}

}  // namespace

// Plan (upload, limits, passes), then per pass draw, read back and reduce into the counts.
OcclusionGrid voxelizeGpu(const Scene& scene, const GridGeometry& geometry, Reporter& reporter,
                          VoxelizeTimings* timings) {
    checkGridSize(geometry);
    VoxelizeTimings time;
    Timer setupTimer;
    GpuContext context;  // declared first: GL objects below are deleted while it is current
    GlProgram program(compileProgram({"glsl/voxelize.vert", "glsl/voxelize.frag"}));
    time.setup = setupTimer.seconds();

    Timer uploadTimer;
    OcclusionGrid grid(geometry);
    const VoxelTriangles tris = prepareVoxelTriangles(scene, geometry);
    const TriangleLists lists = listTriangles(tris, geometry.dims);
    GlObjects gl;
    uploadTriangles(tris, lists, gl);
    const DriverLimits limits;
    IVec2 texSize;
    const std::vector<Pass> passes = planPasses(geometry.dims, limits, texSize);
    setUpTarget(gl, program, texSize);
    const PassUniforms uniforms(program);
    glFinish();
    context.check("voxelizer upload");
    time.upload = uploadTimer.seconds();

    reporter.begin("voxelizing (gpu)", int64_t(passes.size()), "passes");
    std::vector<uint32_t> pixels(size_t(texSize.x) * size_t(texSize.y) * 4);
    for (const Pass& pass : passes) {
        throwIfStopped();
        Timer rasterTimer;
        drawPass(pass, geometry.dims, limits, uniforms, lists, tris.count(), gl);
        time.raster += rasterTimer.seconds();

        Timer readTimer;
        glReadPixels(0, 0, pass.tileWidth, pass.tileHeight, GL_RGBA_INTEGER, GL_UNSIGNED_INT, pixels.data());
        context.check("voxelizer raster pass");
        time.readback += readTimer.seconds();

        Timer reduceTimer;
        reducePass(pass, pixels, grid);
        time.reduction += reduceTimer.seconds();
        reporter.advance(1);
    }
    reporter.end();
    time.passes = int(passes.size());
    if (timings) *timings = time;
    return grid;
}

}  // namespace rs

#else  // !RAYSPLAT_HAVE_EGL

namespace rs {

OcclusionGrid voxelizeGpu(const Scene&, const GridGeometry&, Reporter&, VoxelizeTimings*) {
    throw Error(ErrorKind::Gpu, "built without EGL (meson option -Degl=enabled): use the CPU voxelizer (`voxelizer` cpu)");
}

}  // namespace rs

#endif
