// Scenes built in code for tests: exact geometry whose answers are known analytically.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>

#include "config.h"
#include "core/log.h"
#include "render.h"
#include "scene/scene.h"

namespace rs::test {

// A film layer's mean over its pixels and channels.
inline double layerMean(const Film& f, int layer) {
    double s = 0.0;
    for (const Vec3& v : f.layers[layer]) s += double(v.x) + v.y + v.z;
    return s / (3.0 * double(f.pixelCount()));
}

// A fresh directory under the system temp directory, named after the test and removed with
// everything in it.
class TempDir {
public:
    TempDir() {
        static int counter = 0;
        const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
        path_ = std::filesystem::temp_directory_path() /
                ("raysplat_test_" + std::to_string(getpid()) + "_" + std::to_string(counter++) + "_" +
                 (info ? std::string(info->test_suite_name()) + "_" + info->name() : std::string("x")));
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    std::string file(const std::string& name) const { return (path_ / name).string(); }
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

// Appends triangle (a, b, c) (counter-clockwise = front) with flat normals.
inline void addTriangle(Scene& s, Vec3 a, Vec3 b, Vec3 c, uint32_t material) {
    Vec3 n = glm::normalize(glm::cross(b - a, c - a));
    for (const Vec3& p : {a, b, c}) {
        s.positions.push_back(p);
        s.normals.push_back(n);
        s.uvs.push_back(Vec2(0.f));
    }
    s.triMaterial.push_back(material);
    if (s.objectNames.empty()) s.objectNames.push_back("test object");
    s.triObject.push_back(0);
}

// Quad with corners a, b, c, d in counter-clockwise order seen from its front.
inline void addQuad(Scene& s, Vec3 a, Vec3 b, Vec3 c, Vec3 d, uint32_t material) {
    addTriangle(s, a, b, c, material);
    addTriangle(s, a, c, d, material);
}

// Axis-aligned box; faces point outwards (or inwards when `inward`).
inline void addBox(Scene& s, Vec3 lo, Vec3 hi, uint32_t material, bool inward = false) {
    Vec3 c[8];
    for (int i = 0; i < 8; ++i) c[i] = Vec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) {
        if (inward) addQuad(s, c[f[3]], c[f[2]], c[f[1]], c[f[0]], material);
        else addQuad(s, c[f[0]], c[f[1]], c[f[2]], c[f[3]], material);
    }
}

// Icosphere (subdivided `levels` times) of `radius` around `centre`; normals outwards, or
// inwards (winding and shading normals) when `inward`.
inline void addSphere(Scene& s, Vec3 centre, float radius, int levels, uint32_t material, bool inward = false) {
    const float t = (1.f + std::sqrt(5.f)) / 2.f;
    std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                           {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    std::vector<glm::ivec3> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                                 {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (Vec3& p : v) p = glm::normalize(p);
    for (int l = 0; l < levels; ++l) {
        std::vector<glm::ivec3> g;
        for (const glm::ivec3& tri : f) {
            int m[3];
            for (int e = 0; e < 3; ++e) {
                v.push_back(glm::normalize(v[tri[e]] + v[tri[(e + 1) % 3]]));
                m[e] = int(v.size()) - 1;
            }
            g.push_back({tri[0], m[0], m[2]});
            g.push_back({tri[1], m[1], m[0]});
            g.push_back({tri[2], m[2], m[1]});
            g.push_back({m[0], m[1], m[2]});
        }
        f.swap(g);
    }
    for (const glm::ivec3& tri : f) {
        Vec3 p[3] = {centre + radius * v[tri[0]], centre + radius * v[tri[1]], centre + radius * v[tri[2]]};
        Vec3 n[3] = {v[tri[0]], v[tri[1]], v[tri[2]]};
        if (inward) { std::swap(p[1], p[2]); std::swap(n[1], n[2]); for (Vec3& x : n) x = -x; }
        for (int k = 0; k < 3; ++k) {
            s.positions.push_back(p[k]);
            s.normals.push_back(n[k]);
            s.uvs.push_back(Vec2(0.f));
        }
        s.triMaterial.push_back(material);
        if (s.objectNames.empty()) s.objectNames.push_back("test object");
        s.triObject.push_back(0);
    }
}

inline uint32_t addMaterial(Scene& s, MaterialKind kind, Vec3 baseColor, Vec3 emission = Vec3(0.f)) {
    Material m;
    m.name = "test material " + std::to_string(s.materials.size());
    m.kind = kind;
    m.baseColor = baseColor;
    m.emission = emission;
    if (kind == MaterialKind::Glass) { m.metallic = 0.f; m.roughness = 0.f; }
    s.materials.push_back(m);
    return uint32_t(s.materials.size() - 1);
}

// Appends a w × h linear texture of RGBA texels in [0, 1] (row 0 at v = 0), stored at 16 bits
// a channel; returns its index.
inline int addTexture(Scene& s, int w, int h, const std::vector<Vec4>& texels) {
    std::vector<uint16_t> rgba;
    for (const Vec4& v : texels)
        for (int c = 0; c < 4; ++c) rgba.push_back(uint16_t(std::lround(std::clamp(v[c], 0.f, 1.f) * 65535.f)));
    s.textures.push_back(Texture("test texture " + std::to_string(s.textures.size()), w, h, rgba.data(), false, true));
    return int(s.textures.size()) - 1;
}

// A camera at `from` looking at `to`, square, of vertical field `yfov` (radians).
inline Camera lookAt(Vec3 from, Vec3 to, Vec3 up, float yfov) {
    Camera c;
    c.position = from;
    c.forward = glm::normalize(to - from);
    c.right = glm::normalize(glm::cross(c.forward, up));
    c.up = glm::cross(c.right, c.forward);
    c.yfov = yfov;
    c.aspect = 1.f;
    return c;
}

// Renders `cfg` with 1 and with 2 threads and expects every light layer bit-identical;
// returns the one-thread result.
inline RenderResult expectSamePixelsWhateverTheThreadCount(const Scene& scene, RenderConfig cfg) {
    cfg.threads = 1;
    RenderResult a = render(scene, cfg, silentReporter());
    cfg.threads = 2;
    RenderResult b = render(scene, cfg, silentReporter());
    EXPECT_EQ(a.film.pixelCount(), b.film.pixelCount());
    for (int l = 0; l < kLayerCount && a.film.pixelCount() == b.film.pixelCount(); ++l)
        EXPECT_EQ(0, std::memcmp(a.film.layers[l].data(), b.film.layers[l].data(), a.film.pixelCount() * sizeof(Vec3)))
            << "layer " << layerName(l);
    return a;
}

}  // namespace rs::test
