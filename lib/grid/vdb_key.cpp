// The voxel cache key (docs/design.md §5): a content hash of everything that decides the counts of
// an OcclusionGrid. Kept out of vdb_io.cpp so that hashing does not need OpenVDB.
//
// Hashed, in order: a tag, kVdbFormatVersion, the resolution, the voxelizer kind and its
// supersampling, the triangle count, then the bit patterns of every triangle position (the
// grid geometry follows from them and the resolution), and for cut-out surfaces their alpha
// settings, texture alpha and uvs. MurmurHash3-style mixing of 64-bit
// words with its fmix64 finaliser: not cryptographic, but any change of a vertex bit, of
// the resolution or of the voxelizer settings gives another key with overwhelming odds.
#include <cstdio>
#include <cstring>

#include "grid/vdb_io.h"

namespace rs {

namespace {

class Hasher {
public:
    void add(uint64_t w) {
        w *= 0x87c37b91114253d5ull;
        w = rotl(w, 31);
        w *= 0x4cf5ad432745937full;
        h_ ^= w;
        h_ = rotl(h_, 27) * 5 + 0x52dce729;
        ++words_;
    }
    void add(const std::string& s) {
        add(uint64_t(s.size()));
        for (size_t i = 0; i < s.size(); i += 8) {
            uint64_t w = 0;
            std::memcpy(&w, s.data() + i, std::min<size_t>(8, s.size() - i));
            add(w);
        }
    }
    uint64_t finish() const {
        uint64_t k = h_ ^ words_;
        k ^= k >> 33;
        k *= 0xff51afd7ed558ccdull;
        k ^= k >> 33;
        k *= 0xc4ceb9fe1a85ec53ull;
        k ^= k >> 33;
        return k;
    }

private:
    static uint64_t rotl(uint64_t x, int r) { return (x << r) | (x >> (64 - r)); }
    uint64_t h_ = 0x9e3779b97f4a7c15ull;
    uint64_t words_ = 0;
};

}  // namespace

const char* voxelizerName(VoxelizerKind kind) { return kind == VoxelizerKind::Gpu ? "gpu" : "cpu"; }

std::string cacheKey(const Scene& scene, int resolution, VoxelizerKind kind) {
    Hasher h;
    h.add(std::string("raysplat occlusion grid"));
    h.add(uint64_t(kVdbFormatVersion));
    h.add(uint64_t(uint32_t(resolution)));
    h.add(std::string(voxelizerName(kind)));
    h.add(uint64_t(kVoxelizerSupersampling));
    h.add(uint64_t(scene.positions.size()));
    // Two floats a word; an odd tail word is padded with zeros (the count above keeps
    // "a, b" and "a, b, 0" apart).
    const size_t n = scene.positions.size() * 3;
    const float* f = n ? &scene.positions[0].x : nullptr;
    static_assert(sizeof(Vec3) == 3 * sizeof(float), "Vec3 must be three packed floats");
    for (size_t i = 0; i < n; i += 2) {
        uint32_t a = 0, b = 0;
        std::memcpy(&a, f + i, 4);
        if (i + 1 < n) std::memcpy(&b, f + i + 1, 4);
        h.add(uint64_t(a) | (uint64_t(b) << 32));
    }
    // Cut-out surfaces (alphaMode MASK, BLEND) decide coverage too: each cut-out material's
    // alpha settings and texture alpha, then each cut-out triangle's material and uvs.
    auto bitsOf = [](float x) {
        uint32_t b;
        std::memcpy(&b, &x, 4);
        return uint64_t(b);
    };
    if (scene.hasCutouts()) {
        for (const Material& m : scene.materials) {
            if (m.alphaMode == AlphaMode::Opaque) continue;
            const TextureRef& ref = m.baseColorTexture;
            h.add(uint64_t(m.alphaMode) << 32 | uint64_t(uint32_t(ref.texture)));
            h.add(bitsOf(m.opacity) | bitsOf(m.alphaCutoff) << 32);
            if (!ref.present()) continue;
            h.add(uint64_t(uint32_t(ref.texCoord)) << 32 | bitsOf(ref.transform.rotation));
            h.add(bitsOf(ref.transform.offset.x) | bitsOf(ref.transform.offset.y) << 32);
            h.add(bitsOf(ref.transform.scale.x) | bitsOf(ref.transform.scale.y) << 32);
            const Texture& tex = scene.textures[size_t(ref.texture)];
            h.add(uint64_t(uint32_t(tex.width())) << 32 | uint64_t(uint32_t(tex.height())));
            if (!tex.hasAlpha()) continue;
            for (int i = 0; i < tex.width() * tex.height(); ++i) h.add(bitsOf(tex.alphaAt(i)));
        }
        for (size_t t = 0; t < scene.triangleCount(); ++t) {
            if (scene.materials[scene.triMaterial[t]].alphaMode == AlphaMode::Opaque) continue;
            h.add(uint64_t(t) << 32 | scene.triMaterial[t]);
            for (int k = 0; k < 3; ++k) h.add(bitsOf(scene.uvs[3 * t + k].x) | bitsOf(scene.uvs[3 * t + k].y) << 32);
            for (size_t k = 0; k < 3 && !scene.uvs1.empty(); ++k)
                h.add(bitsOf(scene.uvs1[3 * t + k].x) | bitsOf(scene.uvs1[3 * t + k].y) << 32);
        }
    }
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", (unsigned long long)h.finish());
    return buf;
}

}  // namespace rs
