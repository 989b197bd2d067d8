// vdb_io and the grid stage's voxel cache: OcclusionGrid ⇄ .vdb round trip, the derived
// density/normal grids against values computed here from the counts, the file's transform
// against the glTF → Blender mapping written out by hand, unreadable files, and the cache
// (miss → write, hit, stale, corrupt) through buildGrid with the CPU voxelizer (no EGL).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include "core/error.h"
#include "grid/grid_stage.h"
#include "test_scenes.h"
#include "grid/vdb_io.h"
#include "grid/voxelize.h"

using namespace rs;
using rs::test::TempDir;
namespace fs = std::filesystem;

namespace {

// A grid with arbitrary geometry and random counts 0…16 in ~30 % of the voxels (some sides
// zero, every count value present).
OcclusionGrid randomGrid(uint32_t seed) {
    GridGeometry g;
    g.origin = Vec3(-1.3f, 0.27f, 5.1f);
    g.voxelSize = 0.037f;
    g.dims = IVec3(13, 7, 21);
    OcclusionGrid grid(g);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::uniform_int_distribution<int> count(0, kSubsamples);
    for (size_t i = 0; i < g.voxelCount(); ++i) {
        if (u(rng) > 0.3f) continue;
        for (int s = 0; s < kSideCount; ++s) grid.voxel(i)[s] = u(rng) < 0.4f ? 0 : uint8_t(count(rng));
    }
    // Make sure the extremes are there.
    for (int s = 0; s < kSideCount; ++s) grid.voxel(0)[s] = uint8_t(kSubsamples);
    grid.voxel(1)[kNegZ] = 1;
    return grid;
}

VdbMetadata someMetadata() {
    VdbMetadata m;
    m.cacheKey = "0123456789abcdef";
    m.voxelizer = "cpu";
    m.scene = "some/scene.gltf";
    m.sceneBounds.extend(Vec3(-1, 0, 5));
    m.sceneBounds.extend(Vec3(-0.9f, 0.4f, 5.8f));
    return m;
}

Vec3 apply(const double m[4][4], Vec3 p) {
    Vec3 out;
    for (int r = 0; r < 3; ++r) out[r] = float(m[r][0] * p.x + m[r][1] * p.y + m[r][2] * p.z + m[r][3]);
    return out;
}

std::string readBytes(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

void writeBytes(const std::string& path, const std::string& bytes) {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f.write(bytes.data(), std::streamsize(bytes.size()));
}

void expectIoErrorNaming(const std::string& path) {
    try {
        readVdb(path);
        ADD_FAILURE() << "readVdb(" << path << ") did not throw";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Io) << e.what();
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "not one line: " << e.what();
    }
}

// Two boxes, a floor and a slanted quad: every side of the voxels is met.
Scene cacheScene(float shift = 0.f) {
    Scene s;
    s.path = "vdb_test scene";
    test::addMaterial(s, MaterialKind::Lambert, Vec3(0.5f));
    test::addBox(s, Vec3(-1, 0, -1), Vec3(1, 2, 1), 0, /*inward=*/true);
    test::addBox(s, Vec3(-0.5f + shift, 0, -0.3f), Vec3(0.1f + shift, 0.9f, 0.4f), 0);
    test::addQuad(s, Vec3(0.2f, 0.1f, 0.2f), Vec3(0.8f, 0.3f, 0.2f), Vec3(0.8f, 1.1f, 0.7f), Vec3(0.2f, 0.9f, 0.7f), 0);
    s.computeBounds();
    return s;
}

class RecordingReporter : public Reporter {
public:
    void warn(const std::string& m) override { warnings.push_back(m); }
    std::vector<std::string> warnings;
};

double count(const Stats& stats, const std::string& name) {
    for (const auto& [n, v] : stats.counts)
        if (n == name) return v;
    ADD_FAILURE() << "no count " << name;
    return -1;
}

RenderConfig cacheConfig(const std::string& dir) {
    RenderConfig cfg;
    cfg.grid = 24;
    cfg.voxelizer = "cpu";
    cfg.cacheDir = dir;
    return cfg;
}

OcclusionGrid reference(const Scene& scene, int resolution) {
    ThreadPool pool(2);
    return voxelizeCpu(scene, gridForBounds(scene.bounds, resolution), pool, silentReporter());
}

}  // namespace

// -- The file ---------------------------------------------------------------------------------

TEST(VdbFile, RoundTripKeepsEveryCountAndTheGeometry) {
    TempDir dir;
    OcclusionGrid grid = randomGrid(1);
    std::string path = dir.file("grid.vdb");
    writeVdb(path, grid, someMetadata());
    VdbFile back = readVdb(path);

    EXPECT_EQ(back.grid.geometry.dims, grid.geometry.dims);
    EXPECT_EQ(back.grid.geometry.voxelSize, grid.geometry.voxelSize);  // bit for bit
    EXPECT_EQ(back.grid.geometry.origin, grid.geometry.origin);
    ASSERT_EQ(back.grid.counts.size(), grid.counts.size());
    EXPECT_TRUE(back.grid.counts == grid.counts);
    EXPECT_EQ(back.metadata.cacheKey, "0123456789abcdef");
    EXPECT_EQ(back.metadata.voxelizer, "cpu");
    EXPECT_EQ(back.metadata.supersampling, 4);
    EXPECT_EQ(back.metadata.formatVersion, kVdbFormatVersion);
    EXPECT_EQ(back.metadata.scene, "some/scene.gltf");
    EXPECT_EQ(back.metadata.sceneBounds.lo, someMetadata().sceneBounds.lo);
    EXPECT_EQ(back.metadata.sceneBounds.hi, someMetadata().sceneBounds.hi);
    EXPECT_NE(back.metadata.generator.find("raysplat"), std::string::npos);
    // No temporary file is left beside it.
    int files = 0;
    for (const auto& e : fs::directory_iterator(dir.path())) files += (void(e), 1);
    EXPECT_EQ(files, 1);
}

TEST(VdbFile, EmptyGridRoundTrips) {
    TempDir dir;
    GridGeometry g;
    g.dims = IVec3(3, 4, 5);
    g.voxelSize = 0.5f;
    OcclusionGrid grid(g);
    writeVdb(dir.file("e.vdb"), grid, someMetadata());
    VdbFile back = readVdb(dir.file("e.vdb"));
    EXPECT_EQ(back.grid.geometry.dims, g.dims);
    EXPECT_EQ(back.grid.occupiedCount(), 0u);
}

TEST(VdbFile, DensityNormalAndRatioGridsHoldTheDerivedValues) {
    TempDir dir;
    OcclusionGrid grid = randomGrid(2);
    const GridGeometry& g = grid.geometry;
    std::string path = dir.file("grid.vdb");
    writeVdb(path, grid, someMetadata());
    std::vector<VdbGridDump> grids = dumpVdb(path);

    std::set<std::string> names;
    for (const auto& d : grids) names.insert(d.name);
    EXPECT_EQ(names, (std::set<std::string>{"density", "normal", "occ_px", "occ_nx", "occ_py", "occ_ny", "occ_pz", "occ_nz"}));

    // The occupied voxels, and their values computed here from the raw counts.
    std::map<std::tuple<int, int, int>, size_t> occupied;
    for (int z = 0; z < g.dims.z; ++z)
        for (int y = 0; y < g.dims.y; ++y)
            for (int x = 0; x < g.dims.x; ++x) {
                size_t i = g.index(x, y, z);
                const uint8_t* c = grid.voxel(i);
                if (c[0] + c[1] + c[2] + c[3] + c[4] + c[5] > 0) occupied[{x, y, z}] = i;
            }
    ASSERT_GT(occupied.size(), 100u);

    const char* occNames[6] = {"occ_px", "occ_nx", "occ_py", "occ_ny", "occ_pz", "occ_nz"};
    for (const VdbGridDump& d : grids) {
        SCOPED_TRACE(d.name);
        EXPECT_EQ(d.coords.size(), occupied.size()) << "only occupied voxels are active";
        if (d.name == "density") {
            EXPECT_EQ(d.valueType, "float");
            EXPECT_EQ(d.gridClass, "fog volume");
        } else if (d.name == "normal") {
            EXPECT_EQ(d.valueType, "vec3s");
        } else {
            EXPECT_EQ(d.valueType, "float");
        }
        for (size_t v = 0; v < d.coords.size(); ++v) {
            auto it = occupied.find({d.coords[v].x, d.coords[v].y, d.coords[v].z});
            ASSERT_NE(it, occupied.end());
            const uint8_t* c = grid.voxel(it->second);
            if (d.name == "density") {
                int mx = std::max({c[0], c[1], c[2], c[3], c[4], c[5]});
                EXPECT_EQ(d.values[v].x, float(mx) / 16.f);
            } else if (d.name == "normal") {
                Vec3 n(float(c[0]) - float(c[1]), float(c[2]) - float(c[3]), float(c[4]) - float(c[5]));
                float len = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
                Vec3 expected = len > 0 ? n / len : Vec3(0.f);
                for (int a = 0; a < 3; ++a) EXPECT_NEAR(d.values[v][a], expected[a], 1e-6f);
            } else {
                int side = int(std::find(occNames, occNames + 6, d.name) - occNames);
                ASSERT_LT(side, 6);
                EXPECT_EQ(d.values[v].x, float(c[side]) / 16.f);
            }
        }
    }
}

TEST(VdbFile, TransformPutsVoxelCentresAtTheirBlenderWorldPosition) {
    TempDir dir;
    OcclusionGrid grid = randomGrid(3);
    const GridGeometry& g = grid.geometry;
    std::string path = dir.file("grid.vdb");
    writeVdb(path, grid, someMetadata());
    std::vector<VdbGridDump> grids = dumpVdb(path);
    ASSERT_EQ(grids.size(), 8u);
    for (const VdbGridDump& d : grids) {
        SCOPED_TRACE(d.name);
        for (IVec3 ijk : {IVec3(0, 0, 0), IVec3(12, 6, 20), IVec3(3, 5, 17), IVec3(1, 0, 0), IVec3(0, 1, 0), IVec3(0, 0, 1)}) {
            // glTF world of the voxel's centre, then Blender's importer: (x, y, z) → (x, −z, y).
            double cx = double(g.origin.x) + (ijk.x + 0.5) * g.voxelSize;
            double cy = double(g.origin.y) + (ijk.y + 0.5) * g.voxelSize;
            double cz = double(g.origin.z) + (ijk.z + 0.5) * g.voxelSize;
            Vec3 expected(float(cx), float(-cz), float(cy));
            Vec3 got = apply(d.worldFromIndex, Vec3(ijk));
            for (int a = 0; a < 3; ++a) EXPECT_NEAR(got[a], expected[a], 1e-5f) << "voxel " << ijk.x << "," << ijk.y << "," << ijk.z;
        }
        // A proper rotation times the voxel size: no mirroring, so normals are not flipped.
        const auto& m = d.worldFromIndex;
        double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        EXPECT_NEAR(det, std::pow(double(g.voxelSize), 3), 1e-9);
    }
}

TEST(VdbFile, MissingFileIsAnIoErrorNamingIt) {
    TempDir dir;
    expectIoErrorNaming(dir.file("does_not_exist.vdb"));
}

TEST(VdbFile, TruncatedFilesAreIoErrorsNamingThem) {
    TempDir dir;
    std::string good = dir.file("good.vdb");
    writeVdb(good, randomGrid(4), someMetadata());
    std::string bytes = readBytes(good);
    ASSERT_GT(bytes.size(), 1000u);
    // Cut everywhere in the first few hundred bytes (header, metadata, descriptors), then at
    // spread-out places in the grids.
    std::vector<size_t> cuts;
    for (size_t n = 0; n < 400; n += 7) cuts.push_back(n);
    for (int k = 1; k < 40; ++k) cuts.push_back(bytes.size() * k / 40);
    cuts.push_back(bytes.size() - 1);
    for (size_t n : cuts) {
        SCOPED_TRACE("truncated to " + std::to_string(n) + " bytes");
        std::string path = dir.file("cut.vdb");
        writeBytes(path, bytes.substr(0, n));
        expectIoErrorNaming(path);
    }
}

// The cache's files carry a checksum that is checked before OpenVDB reads them: any flipped
// byte is a clean Io error, even one OpenVDB would have parsed (or allocated exabytes for:
// tests/fuzz/regressions/vdb/found_blosc_length_7_exabytes.vdb).
TEST(VdbFile, CacheFilesWithAnyChangedByteAreRefusedByTheirChecksum) {
    TempDir dir;
    const std::string good = dir.file("good.vdb");
    writeCacheVdb(good, randomGrid(4), someMetadata());
    EXPECT_EQ(readCacheVdb(good).grid.counts, readVdb(good).grid.counts) << "still a VDB to OpenVDB";
    const std::string bytes = readBytes(good);
    std::mt19937 rng(11);
    for (int k = 0; k < 40; ++k) {
        std::string changed = bytes;
        const size_t at = rng() % changed.size();
        changed[at] = char(changed[at] ^ (1 + rng() % 255));
        const std::string path = dir.file("changed.vdb");
        writeBytes(path, changed);
        try {
            readCacheVdb(path);
            ADD_FAILURE() << "byte " << at << " changed, and the cache file was accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::Io);
            EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        }
    }
    const std::string plain = dir.file("plain.vdb");
    writeVdb(plain, randomGrid(4), someMetadata());
    EXPECT_THROW(readCacheVdb(plain), Error) << "a VDB without the trailer is not a cache file";
}

TEST(VdbFile, RandomBytesAndForeignFilesAreIoErrors) {
    TempDir dir;
    std::mt19937 rng(5);
    for (size_t size : {1u, 8u, 100u, 5000u}) {
        std::string bytes(size, '\0');
        for (char& c : bytes) c = char(rng());
        std::string path = dir.file("random.vdb");
        writeBytes(path, bytes);
        expectIoErrorNaming(path);
    }
    // Random bytes after a valid header: the VDB magic number and the first bytes of a real file.
    std::string good = dir.file("good.vdb");
    writeVdb(good, randomGrid(6), someMetadata());
    std::string bytes = readBytes(good);
    for (size_t keep : {8u, 32u, 64u}) {
        std::string b = bytes;
        for (size_t i = keep; i < b.size(); ++i) b[i] = char(rng());
        std::string path = dir.file("garbled.vdb");
        writeBytes(path, b);
        expectIoErrorNaming(path);
    }
    // A text file.
    std::string text = dir.file("scene.gltf");
    writeBytes(text, "{\"asset\": {\"version\": \"2.0\"}}\n");
    expectIoErrorNaming(text);
}

TEST(VdbFile, WriteFailureNamesTheFileAndLeavesNothing) {
    TempDir dir;
    std::string path = dir.file("no_such_dir/grid.vdb");
    try {
        writeVdb(path, randomGrid(7), someMetadata());
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Io);
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    EXPECT_TRUE(fs::is_empty(dir.path()));
}

// -- The cache key ----------------------------------------------------------------------------

TEST(CacheKey, ChangesWithGeometryResolutionAndVoxelizer) {
    Scene a = cacheScene();
    std::string key = cacheKey(a, 24, VoxelizerKind::Cpu);
    EXPECT_EQ(key.size(), 16u);
    EXPECT_EQ(key, cacheKey(cacheScene(), 24, VoxelizerKind::Cpu)) << "deterministic";
    EXPECT_NE(key, cacheKey(a, 25, VoxelizerKind::Cpu));
    EXPECT_NE(key, cacheKey(a, 24, VoxelizerKind::Gpu));
    Scene b = a;
    uint32_t bits;
    std::memcpy(&bits, &b.positions[17].y, 4);
    bits ^= 1;  // one ulp
    std::memcpy(&b.positions[17].y, &bits, 4);
    EXPECT_NE(key, cacheKey(b, 24, VoxelizerKind::Cpu));
    Scene c = a;
    c.positions.push_back(Vec3(0.f));
    EXPECT_NE(key, cacheKey(c, 24, VoxelizerKind::Cpu));
}

// -- The cache, through the grid stage --------------------------------------------------------

TEST(GridCache, FirstCallMissesAndWritesTheFileSecondCallHits) {
    TempDir dir;
    Scene scene = cacheScene();
    RenderConfig cfg = cacheConfig(dir.file("cache"));  // created on demand
    ThreadPool pool(2);
    RecordingReporter reporter;

    Stats first;
    OcclusionGrid a = buildGrid(scene, cfg.gridSettings(), pool, reporter, first);
    EXPECT_EQ(count(first, "grid_cache_hit"), 0);
    std::string path = cachePath(cfg.cacheDir, cacheKey(scene, cfg.grid, VoxelizerKind::Cpu));
    ASSERT_TRUE(fs::exists(path));
    EXPECT_EQ(readVdb(path).metadata.cacheKey, cacheKey(scene, cfg.grid, VoxelizerKind::Cpu));

    Stats second;
    OcclusionGrid b = buildGrid(scene, cfg.gridSettings(), pool, reporter, second);
    EXPECT_EQ(count(second, "grid_cache_hit"), 1);
    EXPECT_TRUE(reporter.warnings.empty());

    OcclusionGrid expected = reference(scene, cfg.grid);
    EXPECT_GT(expected.occupiedCount(), 0u);
    EXPECT_TRUE(a.counts == expected.counts);
    EXPECT_TRUE(b.counts == expected.counts);
    EXPECT_EQ(b.geometry.dims, expected.geometry.dims);
    EXPECT_EQ(count(second, "voxels"), double(expected.geometry.voxelCount()));
    EXPECT_EQ(count(second, "occupied_voxels"), double(expected.occupiedCount()));
    EXPECT_EQ(count(second, "grid_bytes"), double(expected.geometry.voxelCount() * 6));
    EXPECT_GT(second.time("voxelize"), 0.0);
}

TEST(GridCache, StaleFileUnderTheKeyIsRecomputedWithAWarning) {
    TempDir dir;
    Scene scene = cacheScene();
    Scene other = cacheScene(0.3f);  // different geometry, different key
    RenderConfig cfg = cacheConfig(dir.path().string());
    std::string key = cacheKey(scene, cfg.grid, VoxelizerKind::Cpu);
    std::string otherKey = cacheKey(other, cfg.grid, VoxelizerKind::Cpu);
    ASSERT_NE(key, otherKey);
    // The other scene's grid, forced under this scene's file name.
    VdbMetadata meta;
    meta.cacheKey = otherKey;
    meta.voxelizer = "cpu";
    std::string path = cachePath(cfg.cacheDir, key);
    writeCacheVdb(path, reference(other, cfg.grid), meta);

    ThreadPool pool(2);
    RecordingReporter reporter;
    Stats stats;
    OcclusionGrid grid = buildGrid(scene, cfg.gridSettings(), pool, reporter, stats);
    EXPECT_EQ(count(stats, "grid_cache_hit"), 0);
    ASSERT_EQ(reporter.warnings.size(), 1u);
    EXPECT_NE(reporter.warnings[0].find("stale"), std::string::npos) << reporter.warnings[0];
    EXPECT_NE(reporter.warnings[0].find(path), std::string::npos) << reporter.warnings[0];
    EXPECT_TRUE(grid.counts == reference(scene, cfg.grid).counts);
    EXPECT_EQ(readVdb(path).metadata.cacheKey, key) << "the stale file is replaced";
}

TEST(GridCache, TamperedGeometryMetadataIsRecomputedWithAWarning) {
    TempDir dir;
    Scene scene = cacheScene();
    RenderConfig cfg = cacheConfig(dir.path().string());
    std::string key = cacheKey(scene, cfg.grid, VoxelizerKind::Cpu);
    // The right key, but a grid whose origin is off by one voxel.
    OcclusionGrid shifted = reference(scene, cfg.grid);
    shifted.geometry.origin.x += shifted.geometry.voxelSize;
    VdbMetadata meta;
    meta.cacheKey = key;
    meta.voxelizer = "cpu";
    std::string path = cachePath(cfg.cacheDir, key);
    writeCacheVdb(path, shifted, meta);

    ThreadPool pool(2);
    RecordingReporter reporter;
    Stats stats;
    OcclusionGrid grid = buildGrid(scene, cfg.gridSettings(), pool, reporter, stats);
    EXPECT_EQ(count(stats, "grid_cache_hit"), 0);
    ASSERT_EQ(reporter.warnings.size(), 1u);
    EXPECT_NE(reporter.warnings[0].find("stale"), std::string::npos) << reporter.warnings[0];
    EXPECT_EQ(grid.geometry.origin, reference(scene, cfg.grid).geometry.origin);

    Stats again;
    buildGrid(scene, cfg.gridSettings(), pool, reporter, again);
    EXPECT_EQ(count(again, "grid_cache_hit"), 1) << "the rewritten file is a hit";
}

TEST(GridCache, CorruptFileIsRecomputedWithAWarningAndReplaced) {
    TempDir dir;
    Scene scene = cacheScene();
    RenderConfig cfg = cacheConfig(dir.path().string());
    ThreadPool pool(2);
    RecordingReporter quiet;
    Stats s0;
    buildGrid(scene, cfg.gridSettings(), pool, quiet, s0);
    std::string path = cachePath(cfg.cacheDir, cacheKey(scene, cfg.grid, VoxelizerKind::Cpu));
    std::string bytes = readBytes(path);
    writeBytes(path, bytes.substr(0, bytes.size() / 2));

    RecordingReporter reporter;
    Stats stats;
    OcclusionGrid grid = buildGrid(scene, cfg.gridSettings(), pool, reporter, stats);
    EXPECT_EQ(count(stats, "grid_cache_hit"), 0);
    ASSERT_EQ(reporter.warnings.size(), 1u);
    EXPECT_NE(reporter.warnings[0].find(path), std::string::npos) << reporter.warnings[0];
    EXPECT_TRUE(grid.counts == reference(scene, cfg.grid).counts);
    EXPECT_EQ(readBytes(path).size(), bytes.size()) << "the corrupt file is replaced";
    EXPECT_NO_THROW(readVdb(path));
}

TEST(GridCache, VdbOptionWritesTheGridUsed) {
    TempDir dir;
    Scene scene = cacheScene();
    RenderConfig cfg;
    cfg.grid = 20;
    cfg.voxelizer = "cpu";
    cfg.vdb = dir.file("out.vdb");
    ThreadPool pool(2);
    Stats stats;
    OcclusionGrid grid = buildGrid(scene, cfg.gridSettings(), pool, silentReporter(), stats);
    EXPECT_EQ(count(stats, "grid_cache_hit"), 0);
    VdbFile back = readVdb(cfg.vdb);
    EXPECT_TRUE(back.grid.counts == grid.counts);
    EXPECT_EQ(back.metadata.cacheKey, cacheKey(scene, 20, VoxelizerKind::Cpu));
    EXPECT_EQ(back.metadata.voxelizer, "cpu");
    EXPECT_EQ(back.metadata.scene, scene.path);
}

TEST(GridCache, RejectsBadSettings) {
    Scene scene = cacheScene();
    ThreadPool pool(1);
    Stats stats;
    RenderConfig cfg;
    cfg.voxelizer = "cuda";
    EXPECT_THROW(buildGrid(scene, cfg.gridSettings(), pool, silentReporter(), stats), Error);
    cfg.voxelizer = "cpu";
    cfg.grid = 0;
    EXPECT_THROW(buildGrid(scene, cfg.gridSettings(), pool, silentReporter(), stats), Error);
    cfg.grid = 4097;
    EXPECT_THROW(buildGrid(scene, cfg.gridSettings(), pool, silentReporter(), stats), Error);
}
