// Voxelizer tests (docs/design.md §5): both voxelizers against analytic coverage of simple
// surfaces, the mean normal of a sphere, and the GPU against the CPU reference on the
// project's scenes and random triangle soups. GPU tests skip when EGL is unavailable.
#include <gtest/gtest.h>

#include <functional>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>

#include "core/error.h"
#include "grid/gpu_context.h"
#include "grid/shaders.h"
#include "test_scenes.h"
#include "grid/voxelize.h"

using namespace rs;

namespace {

// Whether a GPU context can be made here; the reason when not.
const std::string& gpuUnavailableReason() {
    static const std::string reason = [] {
        try {
            GpuContext context;
            return std::string();
        } catch (const Error& e) {
            return std::string(e.what());
        }
    }();
    return reason;
}
#define SKIP_WITHOUT_GPU()                                                                  \
    do {                                                                                    \
        if (!gpuUnavailableReason().empty()) GTEST_SKIP() << "no GPU: " << gpuUnavailableReason(); \
    } while (0)

GridGeometry unitGrid(IVec3 dims) {
    GridGeometry g;
    g.origin = Vec3(0.f);
    g.voxelSize = 1.f;
    g.dims = dims;
    return g;
}

Scene emptyScene() {
    Scene s;
    s.path = "test scene";
    test::addMaterial(s, MaterialKind::Lambert, Vec3(0.5f));
    return s;
}

OcclusionGrid voxelize(VoxelizerKind kind, Scene& scene, const GridGeometry& grid, int threads = 2) {
    scene.computeBounds();
    if (kind == VoxelizerKind::Gpu) return voxelizeGpu(scene, grid, silentReporter());
    ThreadPool pool(threads);
    return voxelizeCpu(scene, grid, pool, silentReporter());
}

int count(const OcclusionGrid& g, int x, int y, int z, Side s) {
    return g.voxel(g.geometry.index(x, y, z))[s];
}

struct Difference {
    size_t differing = 0, nonZero = 0;  // voxel sides that differ / that are non-zero in either
    int maxCount = 0;                   // largest |count difference|
    double fraction() const { return nonZero ? double(differing) / double(nonZero) : 0.0; }
};

Difference compare(const OcclusionGrid& a, const OcclusionGrid& b) {
    Difference d;
    for (size_t i = 0; i < a.counts.size(); ++i) {
        int x = a.counts[i], y = b.counts[i];
        d.nonZero += (x | y) != 0;
        d.differing += x != y;
        d.maxCount = std::max(d.maxCount, std::abs(x - y));
    }
    return d;
}

// Random soup: small and large triangles, random orientation, inside the grid. With
// `quantum` > 0 the vertices lie on multiples of it (1/8 voxel puts sub-sample centres
// exactly on edges: the fill convention decides).
Scene randomSoup(uint32_t seed, int triangles, IVec3 dims, double quantum = 0.0) {
    Scene s = emptyScene();
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.f, 1.f);
    auto point = [&](Vec3 centre, float size) {
        Vec3 p;
        for (int a = 0; a < 3; ++a) {
            p[a] = std::clamp(centre[a] + size * (2.f * unit(rng) - 1.f), 1.f, float(dims[a] - 1));
            if (quantum > 0) p[a] = float(std::round(p[a] / quantum) * quantum);
        }
        return p;
    };
    for (int t = 0; t < triangles; ++t) {
        Vec3 c(unit(rng) * dims.x, unit(rng) * dims.y, unit(rng) * dims.z);
        float size = t % 10 == 0 ? 0.5f * float(dims.x) : 0.3f + 3.f * unit(rng);
        test::addTriangle(s, point(c, size), point(c, size), point(c, size), 0);
    }
    return s;
}

class Voxelizer : public testing::TestWithParam<VoxelizerKind> {
protected:
    void SetUp() override {
        if (GetParam() == VoxelizerKind::Gpu) SKIP_WITHOUT_GPU();
    }
};

std::string kindName(const testing::TestParamInfo<VoxelizerKind>& info) {
    return info.param == VoxelizerKind::Gpu ? "Gpu" : "Cpu";
}

}  // namespace

// A quad in the plane z = 3.5 covering voxel columns x ∈ [2, 5.5], y ∈ [1, 4]: 16 covered
// sub-samples in full columns, 8 in the half column x = 5, all on +z (or −z flipped).
TEST_P(Voxelizer, AxisAlignedQuadFillsItsVoxelsOnOneSide) {
    for (bool flipped : {false, true}) {
        Scene s = emptyScene();
        Vec3 a(2, 1, 3.5f), b(5.5f, 1, 3.5f), c(5.5f, 4, 3.5f), d(2, 4, 3.5f);
        if (flipped) test::addQuad(s, d, c, b, a, 0);
        else test::addQuad(s, a, b, c, d, 0);
        OcclusionGrid g = voxelize(GetParam(), s, unitGrid(IVec3(8)));
        const Side side = flipped ? kNegZ : kPosZ;
        for (int z = 0; z < 8; ++z)
            for (int y = 0; y < 8; ++y)
                for (int x = 0; x < 8; ++x)
                    for (int k = 0; k < kSideCount; ++k) {
                        bool inside = z == 3 && y >= 1 && y <= 3 && x >= 2 && x <= 5;
                        int expected = inside && k == side ? (x == 5 ? 8 : 16) : 0;
                        ASSERT_EQ(count(g, x, y, z, Side(k)), expected)
                            << "voxel " << x << "," << y << "," << z << " side " << k << " flipped " << flipped;
                    }
    }
}

// A cut-out material (alphaMode MASK or BLEND) with a base colour texture of w × h texels whose
// alpha is alpha(x, y) (8 bits); material 1 of the scene.
uint32_t addCutout(Scene& s, AlphaMode mode, int w, int h, const std::function<float(int, int)>& alpha) {
    const uint32_t m = test::addMaterial(s, MaterialKind::Lambert, Vec3(0.5f));
    std::vector<uint8_t> rgba(4 * size_t(w) * size_t(h), 255);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) rgba[4 * (size_t(y) * size_t(w) + size_t(x)) + 3] = uint8_t(std::lround(255.f * alpha(x, y)));
    s.materials[m].baseColorTexture.texture = int(s.textures.size());
    s.materials[m].alphaMode = mode;
    s.textures.push_back(Texture("cutout", w, h, rgba.data(), true, true));
    return m;
}

// Sets the uvs of the last triangle added.
void setUvs(Scene& s, Vec2 a, Vec2 b, Vec2 c) {
    const size_t n = s.uvs.size();
    s.uvs[n - 3] = a, s.uvs[n - 2] = b, s.uvs[n - 1] = c;
}

// A quad z = 3.5 over x, y ∈ [0, 8] textured by a 2 × 2 checker of alpha 1 and 0 (uv = xy/8),
// alphaMode MASK: the voxel columns under the solid texels are covered, the others not. With
// BLEND and a uniform alpha of 0.3 about 30 % of the sub-samples are.
TEST_P(Voxelizer, CutoutCoversItsSolidTexelsOnly) {
    Scene s = emptyScene();
    const uint32_t m = addCutout(s, AlphaMode::Mask, 2, 2, [](int x, int y) { return (x + y) % 2 ? 0.f : 1.f; });
    test::addTriangle(s, {0, 0, 3.5f}, {8, 0, 3.5f}, {8, 8, 3.5f}, m);
    setUvs(s, {0, 0}, {1, 0}, {1, 1});
    test::addTriangle(s, {0, 0, 3.5f}, {8, 8, 3.5f}, {0, 8, 3.5f}, m);
    setUvs(s, {0, 0}, {1, 1}, {0, 1});
    OcclusionGrid g = voxelize(GetParam(), s, unitGrid(IVec3(8)));
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            const bool solid = (x / 4 + y / 4) % 2 == 0;
            ASSERT_EQ(count(g, x, y, 3, kPosZ), solid ? 16 : 0) << "voxel " << x << "," << y;
        }
    s.materials[m].alphaMode = AlphaMode::Blend;
    s.textures[0] = Texture("cutout", 2, 2, std::vector<uint8_t>(16, uint8_t(std::lround(0.3f * 255.f))).data(), true, true);
    g = voxelize(GetParam(), s, unitGrid(IVec3(8)));
    int covered = 0;
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) covered += count(g, x, y, 3, kPosZ);
    EXPECT_NEAR(covered / (64.0 * 16.0), 0.3, 0.03);
}

// The plane z = x + 5/16 (normal ∝ (−1, 0, 1)) over x ∈ [1, 6], y ∈ [1, 7]: every voxel
// side's count equals the number of its sub-sample centres whose projection hits the
// plane in that voxel, enumerated here in double; no centre lies on a boundary.
TEST_P(Voxelizer, TiltedPlaneMatchesAnalyticCoverage) {
    const double c = 5.0 / 16.0;
    Scene s = emptyScene();
    test::addQuad(s, Vec3(1, 1, 1 + c), Vec3(6, 1, 6 + c), Vec3(6, 7, 6 + c), Vec3(1, 7, 1 + c), 0);
    const GridGeometry geometry = unitGrid(IVec3(8));
    OcclusionGrid g = voxelize(GetParam(), s, geometry);

    OcclusionGrid expected(geometry);
    for (int m = 0; m < 32; ++m)
        for (int n = 0; n < 32; ++n) {
            double p = (m + 0.5) / 4, q = (n + 0.5) / 4;
            // Along z, sub-sample (x, y) = (p, q): the plane is at z = x + c, facing +z.
            if (p > 1 && p < 6 && q > 1 && q < 7)
                expected.voxel(geometry.index(int(p), int(q), int(std::floor(p + c))))[kPosZ]++;
            // Along x, sub-sample (y, z) = (p, q): the plane is at x = z − c, facing −x.
            if (p > 1 && p < 7 && q - c > 1 && q - c < 6)
                expected.voxel(geometry.index(int(std::floor(q - c)), int(p), int(q)))[kNegX]++;
        }
    Difference d = compare(g, expected);
    EXPECT_EQ(d.differing, 0u) << "max count difference " << d.maxCount;

    // Independent of the enumeration: each fully covered column holds exactly 16 hits.
    for (int y = 1; y < 7; ++y)
        for (int x = 1; x < 6; ++x) {
            int sum = 0;
            for (int z = 0; z < 8; ++z) sum += count(g, x, y, z, kPosZ);
            EXPECT_EQ(sum, 16) << "z column " << x << "," << y;
        }
    for (int z = 2; z < 6; ++z)
        for (int y = 1; y < 7; ++y) {
            int sum = 0;
            for (int x = 0; x < 8; ++x) sum += count(g, x, y, z, kNegX);
            EXPECT_EQ(sum, 16) << "x column " << y << "," << z;
        }
}

// A closed box with outward normals: +a on the wall at the box's max along a, −a on the
// min wall, each side's total = 16 × the wall's area in voxel faces; inward flips them.
TEST_P(Voxelizer, ClosedBoxHasFrontAndBackOnOppositeWalls) {
    const Vec3 lo(1.5f, 1.5f, 1.5f), hi(5.5f, 6.5f, 4.5f);
    for (bool inward : {false, true}) {
        Scene s = emptyScene();
        test::addBox(s, lo, hi, 0, inward);
        OcclusionGrid g = voxelize(GetParam(), s, unitGrid(IVec3(8)));
        for (int a = 0; a < 3; ++a) {
            const int u = (a + 1) % 3, v = (a + 2) % 3;
            const int wallArea = int((hi[u] - lo[u]) * (hi[v] - lo[v]) * 16);
            for (int sign = 0; sign < 2; ++sign) {
                const Side side = Side(2 * a + sign);
                // Outward: +a on the max wall. Inward: +a on the min wall.
                const int wall = int(std::floor((sign == 0) != inward ? hi[a] : lo[a]));
                int total = 0;
                for (int z = 0; z < 8; ++z)
                    for (int y = 0; y < 8; ++y)
                        for (int x = 0; x < 8; ++x) {
                            int n = count(g, x, y, z, side);
                            total += n;
                            if (n) {
                                EXPECT_EQ(IVec3(x, y, z)[a], wall) << "side " << side << " inward " << inward;
                            }
                        }
                EXPECT_EQ(total, wallArea) << "side " << side << " inward " << inward;
            }
        }
    }
}

// Paper Fig. 3: the mean normal (c+x − c−x, …) of a voxel on a sphere points along the
// sphere's normal at the voxel centre. Measured (radius 11 voxels, 5120 triangles, 2000
// occupied voxels): CPU and GPU alike median 4.06°, 95th percentile 12.07°, max 25.2°.
TEST_P(Voxelizer, SphereMeanNormalsFollowTheSurface) {
    const Vec3 centre(16.f, 16.f, 16.f);
    Scene s = emptyScene();
    test::addSphere(s, centre, 11.f, 4, 0);
    OcclusionGrid g = voxelize(GetParam(), s, unitGrid(IVec3(32)));
    std::vector<double> angles;
    for (int z = 0; z < 32; ++z)
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x) {
                size_t i = g.geometry.index(x, y, z);
                if (!g.occupied(i)) continue;
                Vec3 n = g.meanNormal(i);
                ASSERT_GT(glm::length(n), 0.f) << "occupied voxel with a zero mean normal";
                Vec3 truth = glm::normalize(Vec3(x, y, z) + 0.5f - centre);
                double cosine = std::clamp(double(glm::dot(glm::normalize(n), truth)), -1.0, 1.0);
                angles.push_back(std::acos(cosine) * 180.0 / M_PI);
            }
    ASSERT_GT(angles.size(), 1000u);
    std::sort(angles.begin(), angles.end());
    double median = angles[angles.size() / 2], p95 = angles[angles.size() * 95 / 100];
    std::printf("sphere: %zu occupied voxels, mean-normal angle median %.2f deg, 95th percentile %.2f deg, max %.2f\n",
                angles.size(), median, p95, angles.back());
    EXPECT_LT(median, 5.0);
    EXPECT_LT(p95, 15.0);
}

// More than 16 GiB of counts is refused with an estimate before anything is allocated.
TEST_P(Voxelizer, RefusesGridsOverTheMemoryLimit) {
    Scene s = emptyScene();
    test::addTriangle(s, Vec3(1, 1, 1), Vec3(2, 1, 1), Vec3(1, 2, 1), 0);
    try {
        voxelize(GetParam(), s, unitGrid(IVec3(2048, 2048, 1024)));
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Config);
        EXPECT_NE(std::string(e.what()).find("24.0 GiB"), std::string::npos) << e.what();
    }
}

INSTANTIATE_TEST_SUITE_P(Both, Voxelizer, testing::Values(VoxelizerKind::Cpu, VoxelizerKind::Gpu), kindName);

TEST(VoxelizeCpu, ResultDoesNotDependOnThreadCount) {
    Scene s = randomSoup(7, 2000, IVec3(40));
    OcclusionGrid one = voxelize(VoxelizerKind::Cpu, s, unitGrid(IVec3(40)), 1);
    OcclusionGrid three = voxelize(VoxelizerKind::Cpu, s, unitGrid(IVec3(40)), 3);
    EXPECT_TRUE(one.counts == three.counts);
    EXPECT_GT(one.occupiedCount(), 1000u);
}

// -- GPU against the CPU reference -----------------------------------------------------
// Both use the same snapped vertices, integer coverage, fill convention and float plane
// evaluation, and the GPU clips nothing, so they agree bit for bit. Measured on llvmpipe:
// identical on every scene and soup below (0 differing sides). Clipping at the interval's
// near/far planes instead of depth clamp made ~3e-5 of the sides differ by one sub-sample.

void expectAgreement(Scene& s, const GridGeometry& geometry, const std::string& what) {
    OcclusionGrid cpu = voxelize(VoxelizerKind::Cpu, s, geometry);
    OcclusionGrid gpu = voxelize(VoxelizerKind::Gpu, s, geometry);
    Difference d = compare(cpu, gpu);
    std::printf("%s: %dx%dx%d, %zu occupied voxels, %zu of %zu non-zero sides differ (%.2e), max count difference %d\n",
                what.c_str(), geometry.dims.x, geometry.dims.y, geometry.dims.z, cpu.occupiedCount(), d.differing,
                d.nonZero, d.fraction(), d.maxCount);
    EXPECT_GT(d.nonZero, 0u) << what;
    EXPECT_EQ(d.differing, 0u) << what;
}

TEST(VoxelizeGpu, MatchesCpuOnDataScenes) {
    SKIP_WITHOUT_GPU();
    const char* dir = std::getenv("RAYSPLAT_DATA");
    ASSERT_NE(dir, nullptr) << "RAYSPLAT_DATA is not set";
    int scenes = 0;
    std::vector<std::filesystem::path> files;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    for (const auto& path : files) {
        if (path.extension() != ".gltf" && path.extension() != ".glb") continue;
        Scene s = loadScene(path.string(), silentReporter());
        expectAgreement(s, gridForBounds(s.bounds, 96), path.filename().string());
        ++scenes;
    }
    EXPECT_GT(scenes, 0);
}

// The Bitterli teapot at 256³ (RAYSPLAT_EXTRA_SCENES names a folder holding
// bitterli-teapot/teapot.glb; skipped without it): scripts/device_check.sh runs it on a GPU.
TEST(VoxelizeGpu, MatchesCpuOnTheTeapot) {
    SKIP_WITHOUT_GPU();
    const char* extra = std::getenv("RAYSPLAT_EXTRA_SCENES");
    if (!extra || !*extra) GTEST_SKIP() << "RAYSPLAT_EXTRA_SCENES is not set";
    const std::string path = std::string(extra) + "/bitterli-teapot/teapot.glb";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent";
    Scene s = loadScene(path, silentReporter());
    expectAgreement(s, gridForBounds(s.bounds, 256), "teapot");
}

TEST(VoxelizeGpu, MatchesCpuOnRandomSoups) {
    SKIP_WITHOUT_GPU();
    // 70 slices along y: two intervals (64 + 6).
    const IVec3 dims(48, 70, 56);
    for (uint32_t seed : {1u, 2u, 3u}) {
        Scene s = randomSoup(seed, 3000, dims);
        expectAgreement(s, unitGrid(dims), "soup " + std::to_string(seed));
    }
}

// Random soups of cut-out triangles with random uvs over a random alpha texture, MASK and
// BLEND: the GPU reads the same texel and draws the same hash as the CPU.
TEST(VoxelizeGpu, MatchesCpuOnCutoutSoups) {
    SKIP_WITHOUT_GPU();
    const IVec3 dims(40, 36, 44);
    for (uint32_t seed : {21u, 22u}) {
        Scene s = randomSoup(seed, 2000, dims);
        std::mt19937 rng(seed);
        std::uniform_real_distribution<float> unit(0.f, 1.f);
        const uint32_t mask = addCutout(s, AlphaMode::Mask, 37, 23, [&](int, int) { return unit(rng); });
        const uint32_t blend = addCutout(s, AlphaMode::Blend, 5, 7, [&](int, int) { return unit(rng); });
        for (size_t t = 0; t < s.triangleCount(); ++t) {
            s.triMaterial[t] = t % 3 == 0 ? 0u : t % 3 == 1 ? mask : blend;
            for (int k = 0; k < 3; ++k) s.uvs[3 * t + k] = Vec2(4.f * unit(rng) - 2.f, 4.f * unit(rng) - 2.f);
        }
        expectAgreement(s, unitGrid(dims), "cut-out soup " + std::to_string(seed));
    }
}

// Vertices on the 1/8-voxel lattice put many sub-sample centres exactly on edges and
// vertices: the CPU's fill convention must be the rasterizer's.
TEST(VoxelizeGpu, MatchesCpuWhereSubsamplesLieOnEdges) {
    SKIP_WITHOUT_GPU();
    const IVec3 dims(24);
    for (uint32_t seed : {11u, 12u}) {
        Scene s = randomSoup(seed, 2000, dims, 0.125);
        expectAgreement(s, unitGrid(dims), "lattice soup " + std::to_string(seed));
    }
}

// 4 × 1100 pixels exceed the 4096-pixel tile: the viewport is cut into tiles.
TEST(VoxelizeGpu, TiledViewportMatchesCpu) {
    SKIP_WITHOUT_GPU();
    const IVec3 dims(1100, 6, 7);
    Scene s = randomSoup(21, 3000, dims);
    expectAgreement(s, unitGrid(dims), "wide soup");
}

TEST(VoxelizeGpu, DescribesTheDevice) {
    SKIP_WITHOUT_GPU();
    std::string d = describeGpu();
    std::printf("gpu: %s\n", d.c_str());
    EXPECT_NE(d.find("OpenGL 4."), std::string::npos) << d;
    EXPECT_NE(d.find("EGL"), std::string::npos) << d;
}

#ifdef RAYSPLAT_HAVE_EGL
TEST(Shaders, LogLinesNameFileAndLine) {
    EXPECT_EQ(formatShaderLog("glsl/voxelize.frag", "0:12(3): error: `foo' undeclared\n"),
              "glsl/voxelize.frag:12: error: `foo' undeclared");
    EXPECT_EQ(formatShaderLog("glsl/a.vert", "0(7) : error C1008: undefined variable \"x\"\n"),
              "glsl/a.vert:7: error C1008: undefined variable \"x\"");
    EXPECT_EQ(formatShaderLog("glsl/a.vert", "linker says no\n0:2(1): warning: w\n"),
              "glsl/a.vert: linker says no | glsl/a.vert:2: warning: w");
}

TEST(Shaders, EmbeddedVoxelizerShadersCompile) {
    SKIP_WITHOUT_GPU();
    GpuContext context;
    EXPECT_NE(shaderSource("glsl/voxelize.frag").find("#version 450"), std::string::npos);
    GlProgram program(compileProgram({"glsl/voxelize.vert", "glsl/voxelize.frag"}));
    EXPECT_NE(program.id(), 0u);
    EXPECT_THROW(shaderSource("glsl/missing.frag"), Error);
}

TEST(Shaders, CompileErrorNamesFileAndLine) {
    SKIP_WITHOUT_GPU();
    GpuContext context;
    try {
        compileProgramFromSources({{"glsl/broken.frag", "#version 450 core\nout vec4 c;\nvoid main() {\n  c = nothing;\n}\n"}});
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Gpu);
        EXPECT_NE(std::string(e.what()).find("glsl/broken.frag:4:"), std::string::npos) << e.what();
    }
}
#endif
