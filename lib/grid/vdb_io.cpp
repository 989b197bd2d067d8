// OcclusionGrid ⇄ .vdb (see vdb_io.h for the grids, spaces and metadata). The only
// translation unit that includes OpenVDB (docs/design.md §1: it compiles slowly).
//
// Decisions:
// - The transform is an affine map whose linear part is voxelSize · R, R the proper rotation
//   (x, y, z) → (x, −z, y) of Blender's glTF importer; OpenVDB multiplies row vectors, so
//   row r of the matrix is the Blender-world image of index axis r and row 3 the
//   translation (the centre of voxel (0,0,0)).
// - The normal grid holds the mean normal in index-space axes (= glTF world axes, what
//   OcclusionGrid::meanNormal gives) and is marked VEC_COVARIANT_NORMALIZE: a tool that
//   honours OpenVDB's vector types gets Blender-world normals through the transform.
// - Files are read without delayed loading: a memory-mapped, lazily read file that is
//   truncated could fail long after readVdb returned (SIGBUS); here every byte is read,
//   and checked, before returning.
// - The file's outer structure is walked before OpenVDB reads it (checkOuterStructure).
// - Every count is read back from occ_* as round(16·value) and must be an integer 0…16 at
//   a voxel inside dims: anything else is a corrupt or foreign file.
#include "grid/vdb_io.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <algorithm>
#include <vector>
#include <fstream>
#include <mutex>

#include "core/error.h"
#include "core/stop.h"
#include "core/staged_files.h"

#ifndef RAYSPLAT_VERSION
#define RAYSPLAT_VERSION "dev"
#endif

namespace rs {

namespace {

const char* const kOccNames[kSideCount] = {"occ_px", "occ_nx", "occ_py", "occ_ny", "occ_pz", "occ_nz"};

void initOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

std::string oneLine(std::string s) {
    for (char& c : s)
        if (c == '\n' || c == '\r') c = ' ';
    return s;
}

// Blender's world from glTF's: +Y up → +Z up, (x, y, z) → (x, −z, y).
openvdb::Vec3d blenderFromGltf(const openvdb::Vec3d& p) { return {p.x(), -p.z(), p.y()}; }

// Index (i, j, k) → Blender-world centre of voxel (i, j, k).
openvdb::math::Transform::Ptr blenderWorldFromIndex(const GridGeometry& g) {
    const double s = g.voxelSize;
    openvdb::Mat4d m;
    m.setIdentity();
    const openvdb::Vec3d axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int r = 0; r < 3; ++r) {
        openvdb::Vec3d img = blenderFromGltf(axes[r]) * s;
        for (int c = 0; c < 3; ++c) m(r, c) = img[c];
    }
    openvdb::Vec3d centre0 = blenderFromGltf(openvdb::Vec3d(g.origin.x, g.origin.y, g.origin.z) + 0.5 * s);
    for (int c = 0; c < 3; ++c) m(3, c) = centre0[c];
    return openvdb::math::Transform::createLinearTransform(m);
}

openvdb::Vec3s toVdb(const Vec3& v) { return {v.x, v.y, v.z}; }
Vec3 fromVdb(const openvdb::Vec3s& v) { return {v.x(), v.y(), v.z()}; }

// Reading: a failure anywhere is reported as one Error(Io) naming the file.
struct ReadFailure {
    std::string reason;
};

template <class T>
T require(const openvdb::MetaMap& meta, const std::string& key) {
    auto m = meta.getMetadata<openvdb::TypedMetadata<T>>(key);
    if (!m) throw ReadFailure{"metadata '" + key + "' is missing or has the wrong type"};
    return m->value();
}

// Calls fn(coord) for each active voxel of `grid` (active tiles expanded).
template <class GridT, class Fn>
void forEachActive(const GridT& grid, Fn&& fn) {
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) {
            fn(it.getCoord(), *it);
        } else {
            openvdb::CoordBBox bb;
            it.getBoundingBox(bb);
            if (bb.volume() > (uint64_t(1) << 32)) throw ReadFailure{"an active tile is implausibly large"};
            for (auto c = bb.begin(); c; ++c) fn(*c, *it);
        }
    }
}

}  // namespace

// -- Writing ----------------------------------------------------------------------------------

void writeVdb(const std::string& path, const OcclusionGrid& grid, const VdbMetadata& metadata) {
    StagedFiles out;
    writeVdbTo(out.stage(path), path, grid, metadata);
    out.commit();
}

namespace {

constexpr char kTrailerMagic[8] = {'R', 'S', 'V', 'D', 'B', 'S', 'U', 'M'};

// FNV-1a over the first `bytes` bytes of a file, read in blocks.
uint64_t hashFilePrefix(std::ifstream& in, uint64_t bytes) {
    uint64_t h = 0xcbf29ce484222325ull;
    std::vector<char> block(1 << 20);
    while (bytes > 0) {
        const size_t n = size_t(std::min<uint64_t>(bytes, block.size()));
        if (!in.read(block.data(), std::streamsize(n))) return ~h;
        for (size_t i = 0; i < n; ++i) h = (h ^ uint8_t(block[i])) * 0x100000001b3ull;
        bytes -= n;
    }
    return h;
}

}  // namespace

void writeCacheVdb(const std::string& path, const OcclusionGrid& grid, const VdbMetadata& metadata) {
    StagedFiles out;
    const std::string tmp = out.stage(path);
    writeVdbTo(tmp, path, grid, metadata);
    std::error_code ec;
    const uint64_t size = std::filesystem::file_size(tmp, ec);
    std::ifstream in(tmp, std::ios::binary);
    if (ec || !in) throw Error(ErrorKind::Io, path + ": cannot write the cache file's checksum");
    const uint64_t hash = hashFilePrefix(in, size);
    in.close();
    std::ofstream app(tmp, std::ios::binary | std::ios::app);
    app.write(kTrailerMagic, sizeof kTrailerMagic);
    app.write(reinterpret_cast<const char*>(&hash), sizeof hash);
    app.close();
    if (!app) throw Error(ErrorKind::Io, path + ": cannot write the cache file's checksum");
    out.commit();
}

VdbFile readCacheVdb(const std::string& path) {
    std::error_code ec;
    const uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) throw Error(ErrorKind::Io, path + ": cannot read occlusion grid: no such file");
    std::ifstream in(path, std::ios::binary);
    char magic[sizeof kTrailerMagic] = {};
    uint64_t stored = 0;
    if (size >= 16 && in.seekg(std::streamoff(size - 16)) && in.read(magic, sizeof magic) &&
        in.read(reinterpret_cast<char*>(&stored), sizeof stored) &&
        std::equal(magic, magic + sizeof magic, kTrailerMagic) && in.seekg(0) &&
        hashFilePrefix(in, size - 16) == stored)
        return readVdb(path);
    throw Error(ErrorKind::Io, path + ": not a whole cache file (no checksum, or it does not match its bytes)");
}

void writeVdbTo(const std::string& tmp, const std::string& path, const OcclusionGrid& grid,
                const VdbMetadata& metadata) {
    initOpenVdb();
    const GridGeometry& g = grid.geometry;
    RS_CHECK(grid.counts.size() == g.voxelCount() * kSideCount);

    openvdb::math::Transform::Ptr xform = blenderWorldFromIndex(g);
    openvdb::FloatGrid::Ptr density = openvdb::FloatGrid::create(0.f);
    density->setName("density");
    density->setGridClass(openvdb::GRID_FOG_VOLUME);
    openvdb::Vec3SGrid::Ptr normal = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.f));
    normal->setName("normal");
    normal->setVectorType(openvdb::VEC_COVARIANT_NORMALIZE);
    openvdb::FloatGrid::Ptr occ[kSideCount];
    for (int s = 0; s < kSideCount; ++s) {
        occ[s] = openvdb::FloatGrid::create(0.f);
        occ[s]->setName(kOccNames[s]);
    }

    // Only occupied voxels become active; an empty grid still writes eight empty grids.
    {
        auto dAcc = density->getAccessor();
        auto nAcc = normal->getAccessor();
        openvdb::FloatGrid::Accessor oAcc[kSideCount] = {occ[0]->getAccessor(), occ[1]->getAccessor(),
                                                         occ[2]->getAccessor(), occ[3]->getAccessor(),
                                                         occ[4]->getAccessor(), occ[5]->getAccessor()};
        for (int z = 0; z < g.dims.z; ++z) {
            throwIfStopped();
            for (int y = 0; y < g.dims.y; ++y)
                for (int x = 0; x < g.dims.x; ++x) {
                    size_t i = g.index(x, y, z);
                    if (!grid.occupied(i)) continue;
                    const uint8_t* c = grid.voxel(i);
                    const openvdb::Coord ijk(x, y, z);
                    uint8_t maxCount = 0;
                    for (int s = 0; s < kSideCount; ++s) {
                        oAcc[s].setValueOn(ijk, float(c[s]) / float(kSubsamples));
                        maxCount = std::max(maxCount, c[s]);
                    }
                    dAcc.setValueOn(ijk, float(maxCount) / float(kSubsamples));
                    Vec3 n = grid.meanNormal(i);
                    float len = glm::length(n);
                    nAcc.setValueOn(ijk, toVdb(len > 0.f ? n / len : Vec3(0.f)));
                }
        }
    }

    openvdb::GridPtrVec grids;
    grids.push_back(density);
    grids.push_back(normal);
    for (auto& o : occ) grids.push_back(o);
    for (auto& gr : grids) gr->setTransform(xform);

    openvdb::MetaMap meta;
    meta.insertMeta("raysplat_format", openvdb::Int32Metadata(kVdbFormatVersion));
    meta.insertMeta("raysplat_generator",
                    openvdb::StringMetadata(metadata.generator.empty() ? std::string("raysplat ") + RAYSPLAT_VERSION
                                                                       : metadata.generator));
    meta.insertMeta("raysplat_cache_key", openvdb::StringMetadata(metadata.cacheKey));
    meta.insertMeta("raysplat_voxelizer", openvdb::StringMetadata(metadata.voxelizer));
    meta.insertMeta("raysplat_supersampling", openvdb::Int32Metadata(metadata.supersampling));
    meta.insertMeta("raysplat_dims", openvdb::Vec3IMetadata(openvdb::Vec3i(g.dims.x, g.dims.y, g.dims.z)));
    meta.insertMeta("raysplat_voxel_size", openvdb::FloatMetadata(g.voxelSize));
    meta.insertMeta("raysplat_origin", openvdb::Vec3SMetadata(toVdb(g.origin)));
    meta.insertMeta("raysplat_bounds_min", openvdb::Vec3SMetadata(toVdb(g.origin)));
    meta.insertMeta("raysplat_bounds_max", openvdb::Vec3SMetadata(toVdb(g.worldFromVoxel(Vec3(g.dims)))));
    meta.insertMeta("raysplat_scene", openvdb::StringMetadata(metadata.scene));
    if (!metadata.sceneBounds.empty()) {
        meta.insertMeta("raysplat_scene_bounds_min", openvdb::Vec3SMetadata(toVdb(metadata.sceneBounds.lo)));
        meta.insertMeta("raysplat_scene_bounds_max", openvdb::Vec3SMetadata(toVdb(metadata.sceneBounds.hi)));
    }
    meta.insertMeta("raysplat_occupied_voxels", openvdb::Int64Metadata(int64_t(density->activeVoxelCount())));
    meta.insertMeta("raysplat_space",
                    openvdb::StringMetadata("index (i,j,k) -> centre of voxel (i,j,k) in Blender world; "
                                            "Blender (x,y,z) = glTF (x,-z,y); glTF = origin + voxel*voxel_size"));

    throwIfStopped();  // the write itself cannot be interrupted
    try {
        openvdb::io::File file(tmp);
        file.write(grids, meta);
        file.close();
    } catch (const std::exception& e) {
        std::error_code ec;
        std::filesystem::remove(tmp, ec);
        throw Error(ErrorKind::Io, path + ": cannot write VDB: " + oneLine(e.what()));
    }
}

// -- Reading ----------------------------------------------------------------------------------

namespace {

// OpenVDB's reader trusts every length in the file and does not check the stream after a
// read: in a truncated file it takes garbage for string and metadata lengths and allocates
// gigabytes (a cut in the file metadata took ~15 s to fail). So walk the file's outer
// structure first, checking every length against the file size: header, file metadata,
// and the grid descriptors with their [gridPos, endPos) sections (io::Archive::write and
// GridDescriptor::writeHeader/writeStreamPos in OpenVDB 10). Inside a grid section only
// OpenVDB knows the layout; a file cut anywhere is caught here.
void checkOuterStructure(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw ReadFailure{"cannot open the file"};
    f.seekg(0, std::ios::end);
    const int64_t size = int64_t(f.tellg());
    f.seekg(0);
    int64_t pos = 0;
    auto need = [&](int64_t n, const char* what) {
        if (n < 0 || pos + n > size)
            throw ReadFailure{std::string("truncated or corrupt VDB file (") + what + " at byte " + std::to_string(pos) +
                              " runs past the end, " + std::to_string(size) + " bytes)"};
    };
    auto read = [&](void* dst, int64_t n, const char* what) {
        need(n, what);
        f.read(static_cast<char*>(dst), n);
        if (!f) throw ReadFailure{"read error"};
        pos += n;
    };
    auto skip = [&](int64_t n, const char* what) {
        need(n, what);
        pos += n;
        f.seekg(pos);
    };
    auto skipString = [&](const char* what) {
        uint32_t n = 0;
        read(&n, 4, what);
        skip(n, what);
    };

    int64_t magic = 0;
    read(&magic, 8, "magic number");
    if (magic != int64_t(openvdb::OPENVDB_MAGIC)) throw ReadFailure{"not a VDB file"};
    uint32_t version = 0;
    read(&version, 4, "file version");
    if (version < openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION || version > openvdb::OPENVDB_FILE_VERSION)
        throw ReadFailure{"VDB file format version " + std::to_string(version) + " (raysplat writes " +
                          std::to_string(openvdb::OPENVDB_FILE_VERSION) + ")"};
    skip(8, "library version");
    char hasOffsets = 0;
    read(&hasOffsets, 1, "header");
    if (!hasOffsets) throw ReadFailure{"a VDB stream without grid offsets (raysplat writes files)"};
    skip(36, "UUID");
    uint32_t metaCount = 0;
    read(&metaCount, 4, "metadata count");
    for (uint32_t i = 0; i < metaCount; ++i) {
        skipString("metadata name");
        skipString("metadata type");
        skipString("metadata value");  // Metadata::write: a 32-bit byte count, then the bytes
    }
    int32_t gridCount = 0;
    read(&gridCount, 4, "grid count");
    if (gridCount < 0 || gridCount > 1024) throw ReadFailure{"corrupt VDB file (grid count " + std::to_string(gridCount) + ")"};
    for (int32_t i = 0; i < gridCount; ++i) {
        skipString("grid name");
        skipString("grid type");
        skipString("instance parent");
        int64_t offsets[3];  // grid, block and end position
        read(offsets, sizeof offsets, "grid offsets");
        if (!(offsets[0] == pos && offsets[0] <= offsets[1] && offsets[1] <= offsets[2]))
            throw ReadFailure{"corrupt VDB file (grid offsets of grid " + std::to_string(i) + ")"};
        skip(offsets[2] - pos, "grid data");
    }
}

VdbFile readVdbUnchecked(const std::string& path) {
    checkOuterStructure(path);
    openvdb::io::File file(path);
    file.open(/*delayLoad=*/false);
    openvdb::MetaMap::Ptr metaPtr = file.getMetadata();
    if (!metaPtr || !metaPtr->getMetadata<openvdb::Int32Metadata>("raysplat_format"))
        throw ReadFailure{"not a raysplat occlusion grid (no raysplat_format metadata)"};
    const openvdb::MetaMap& meta = *metaPtr;

    VdbFile out;
    VdbMetadata& md = out.metadata;
    md.formatVersion = require<int32_t>(meta, "raysplat_format");
    if (md.formatVersion != kVdbFormatVersion)
        throw ReadFailure{"format version " + std::to_string(md.formatVersion) + ", this build reads version " +
                          std::to_string(kVdbFormatVersion)};
    md.generator = require<std::string>(meta, "raysplat_generator");
    md.cacheKey = require<std::string>(meta, "raysplat_cache_key");
    md.voxelizer = require<std::string>(meta, "raysplat_voxelizer");
    md.supersampling = require<int32_t>(meta, "raysplat_supersampling");
    md.scene = require<std::string>(meta, "raysplat_scene");
    if (meta.getMetadata<openvdb::Vec3SMetadata>("raysplat_scene_bounds_min")) {
        md.sceneBounds.lo = fromVdb(require<openvdb::Vec3s>(meta, "raysplat_scene_bounds_min"));
        md.sceneBounds.hi = fromVdb(require<openvdb::Vec3s>(meta, "raysplat_scene_bounds_max"));
    }

    GridGeometry g;
    openvdb::Vec3i dims = require<openvdb::Vec3i>(meta, "raysplat_dims");
    g.dims = IVec3(dims.x(), dims.y(), dims.z());
    g.voxelSize = require<float>(meta, "raysplat_voxel_size");
    g.origin = fromVdb(require<openvdb::Vec3s>(meta, "raysplat_origin"));
    if (g.dims.x < 1 || g.dims.y < 1 || g.dims.z < 1 || g.dims.x > 65536 || g.dims.y > 65536 || g.dims.z > 65536 ||
        double(g.dims.x) * g.dims.y * g.dims.z > 1e11)
        throw ReadFailure{"implausible grid dims in metadata"};
    if (!(g.voxelSize > 0.f) || !std::isfinite(g.voxelSize) || !isFinite(g.origin))
        throw ReadFailure{"implausible voxel size or origin in metadata"};

    // Every grid must be there, with the right type and the transform the geometry implies.
    openvdb::math::Transform::Ptr expected = blenderWorldFromIndex(g);
    const double tolerance = 1e-5 * (glm::length(g.origin) + double(maxComponent(Vec3(g.dims))) * g.voxelSize);
    auto readChecked = [&](const std::string& name) -> openvdb::GridBase::Ptr {
        if (!file.hasGrid(name)) throw ReadFailure{"grid '" + name + "' is missing"};
        openvdb::GridBase::Ptr grid = file.readGrid(name);
        if (!grid) throw ReadFailure{"grid '" + name + "' cannot be read"};
        const openvdb::math::Transform& t = grid->transform();
        const openvdb::Vec3d probes[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        for (const auto& p : probes) {
            openvdb::Vec3d d = t.indexToWorld(p) - expected->indexToWorld(p);
            if (!t.isLinear() || !(d.length() <= tolerance))
                throw ReadFailure{"grid '" + name + "' has a transform that does not match the grid geometry in the metadata"};
        }
        return grid;
    };

    out.grid = OcclusionGrid(g);
    OcclusionGrid& og = out.grid;
    for (int s = 0; s < kSideCount; ++s) {
        auto occ = openvdb::gridPtrCast<openvdb::FloatGrid>(readChecked(kOccNames[s]));
        if (!occ) throw ReadFailure{std::string("grid '") + kOccNames[s] + "' is not a float grid"};
        forEachActive(*occ, [&](const openvdb::Coord& c, float v) {
            float scaled = v * float(kSubsamples);
            long n = std::lround(scaled);
            if (!g.contains(c.x(), c.y(), c.z()))
                throw ReadFailure{std::string("grid '") + kOccNames[s] + "' has a voxel outside the grid dims"};
            if (!(std::fabs(scaled - float(n)) <= 1e-3f) || n < 0 || n > kSubsamples)
                throw ReadFailure{std::string("grid '") + kOccNames[s] + "' holds a value that is not a count/16"};
            og.voxel(g.index(c.x(), c.y(), c.z()))[s] = uint8_t(n);
        });
    }
    // density and normal are derived; they must be there (Blender shows them) with their types.
    auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(readChecked("density"));
    if (!density) throw ReadFailure{"grid 'density' is not a float grid"};
    auto normal = openvdb::gridPtrCast<openvdb::Vec3SGrid>(readChecked("normal"));
    if (!normal) throw ReadFailure{"grid 'normal' is not a vec3s grid"};
    size_t occupied = og.occupiedCount();
    if (density->activeVoxelCount() != occupied)
        throw ReadFailure{"grid 'density' has " + std::to_string(density->activeVoxelCount()) +
                          " active voxels, the occ_* grids " + std::to_string(occupied)};
    file.close();
    return out;
}

}  // namespace

VdbFile readVdb(const std::string& path) {
    initOpenVdb();
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        throw Error(ErrorKind::Io, path + ": cannot read occlusion grid: no such file");
    try {
        return readVdbUnchecked(path);
    } catch (const ReadFailure& f) {
        throw Error(ErrorKind::Io, path + ": cannot read occlusion grid: " + oneLine(f.reason));
    } catch (const std::bad_alloc&) {
        throw Error(ErrorKind::Io, path + ": cannot read occlusion grid: corrupt file (out of memory while reading)");
    } catch (const std::exception& e) {
        throw Error(ErrorKind::Io, path + ": cannot read occlusion grid: corrupt or not a VDB file (" +
                                       oneLine(e.what()) + ")");
    }
}

// -- Inspection -------------------------------------------------------------------------------

std::vector<VdbGridDump> dumpVdb(const std::string& path) {
    initOpenVdb();
    std::vector<VdbGridDump> out;
    try {
        openvdb::io::File file(path);
        file.open(false);
        openvdb::GridPtrVecPtr grids = file.getGrids();
        file.close();
        for (const openvdb::GridBase::Ptr& grid : *grids) {
            VdbGridDump d;
            d.name = grid->getName();
            d.valueType = grid->valueType();
            d.gridClass = openvdb::GridBase::gridClassToString(grid->getGridClass());
            const openvdb::math::Transform& t = grid->transform();
            openvdb::Vec3d o = t.indexToWorld(openvdb::Vec3d(0, 0, 0));
            for (int r = 0; r < 4; ++r) d.worldFromIndex[3][r] = r == 3 ? 1.0 : 0.0;
            for (int c = 0; c < 3; ++c) {
                openvdb::Vec3d axis(0, 0, 0);
                axis[c] = 1;
                openvdb::Vec3d img = t.indexToWorld(axis) - o;
                for (int r = 0; r < 3; ++r) d.worldFromIndex[r][c] = img[r];
            }
            for (int r = 0; r < 3; ++r) d.worldFromIndex[r][3] = o[r];
            if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(grid)) {
                forEachActive(*f, [&](const openvdb::Coord& c, float v) {
                    d.coords.emplace_back(c.x(), c.y(), c.z());
                    d.values.emplace_back(v, 0.f, 0.f);
                });
            } else if (auto v = openvdb::gridPtrCast<openvdb::Vec3SGrid>(grid)) {
                forEachActive(*v, [&](const openvdb::Coord& c, const openvdb::Vec3s& x) {
                    d.coords.emplace_back(c.x(), c.y(), c.z());
                    d.values.push_back(fromVdb(x));
                });
            }
            out.push_back(std::move(d));
        }
    } catch (const ReadFailure& f) {
        throw Error(ErrorKind::Io, path + ": cannot read VDB: " + oneLine(f.reason));
    } catch (const std::exception& e) {
        throw Error(ErrorKind::Io, path + ": cannot read VDB: " + oneLine(e.what()));
    }
    return out;
}

}  // namespace rs
