// scene_test: the glTF loader (lib/scene.cpp) against expectations derived independently of
// it — from scripts/make_scenes.py for the scenes in data/, and from transforms, areas and
// windings worked out by hand for small glTF files that the tests write themselves.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <stb/stb_image_write.h>
#include <zlib.h>

#include "core/error.h"
#include "core/log.h"
#include "scene/scene.h"
#include "test_scenes.h"

using namespace rs;
using rs::test::TempDir;
namespace fs = std::filesystem;

namespace {

// -- Helpers ----------------------------------------------------------------------------------

std::string envOr(const char* name, const std::string& fallback) {
    const char* v = std::getenv(name);
    return v && *v ? std::string(v) : fallback;
}

std::string dataPath(const std::string& file) {
    return (fs::path(envOr("RAYSPLAT_DATA", "data")) / file).string();
}

void writeFile(const std::string& path, const std::string& bytes) {
    std::ofstream f(path, std::ios::binary);
    f.write(bytes.data(), std::streamsize(bytes.size()));
    ASSERT_TRUE(f.good()) << path;
}

std::string base64(const std::string& in) {
    static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8 | uint8_t(in[i + 2]);
        for (int s = 18; s >= 0; s -= 6) out += kAlphabet[(v >> s) & 63];
    }
    if (i + 1 == in.size()) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16;
        out += kAlphabet[(v >> 18) & 63];
        out += kAlphabet[(v >> 12) & 63];
        out += "==";
    } else if (i + 2 == in.size()) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8;
        out += kAlphabet[(v >> 18) & 63];
        out += kAlphabet[(v >> 12) & 63];
        out += kAlphabet[(v >> 6) & 63];
        out += '=';
    }
    return out;
}

template <class T>
std::string bytesOf(const std::vector<T>& v) {
    return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

std::string join(const std::vector<std::string>& parts) {
    std::string s;
    for (size_t i = 0; i < parts.size(); ++i) s += (i ? "," : "") + parts[i];
    return s;
}

constexpr int kUByte = 5121, kUShort = 5123, kUInt = 5125, kFloat = 5126;
constexpr int kPoints = 0, kTriangles = 4, kStrip = 5, kFan = 6;

// Builds a small glTF document: one binary buffer, and the JSON objects that refer to it.
class GltfBuilder {
public:
    // Appends `bytes` as a new bufferView; returns its index.
    int view(const std::string& bytes) {
        while (bin_.size() % 4) bin_.push_back('\0');
        size_t offset = bin_.size();
        bin_ += bytes;
        views_.push_back("{\"buffer\":0,\"byteOffset\":" + std::to_string(offset) +
                         ",\"byteLength\":" + std::to_string(bytes.size()) + "}");
        return int(views_.size()) - 1;
    }
    // Appends `bytes` as a new bufferView and an accessor over it; returns the accessor index.
    int accessor(const std::string& bytes, int componentType, int count, const char* type, bool normalized = false) {
        const int v = view(bytes);
        accessors_.push_back("{\"bufferView\":" + std::to_string(v) + ",\"componentType\":" + std::to_string(componentType) +
                             ",\"count\":" + std::to_string(count) + ",\"type\":\"" + type + "\"" +
                             (normalized ? ",\"normalized\":true}" : "}"));
        return int(accessors_.size()) - 1;
    }
    // An accessor without a bufferView: zeros, until a sparse substitution.
    int zeros(int componentType, int count, const char* type) {
        accessors_.push_back("{\"componentType\":" + std::to_string(componentType) + ",\"count\":" + std::to_string(count) +
                             ",\"type\":\"" + type + "\"}");
        return int(accessors_.size()) - 1;
    }
    // Makes accessor `a` sparse: the `count` elements `indices` (of componentType `indexType`)
    // become `values` (of the accessor's own component type).
    void sparse(int a, int count, const std::string& indices, int indexType, const std::string& values) {
        const int iv = view(indices), vv = view(values);
        std::string& s = accessors_[size_t(a)];
        s.pop_back();
        s += ",\"sparse\":{\"count\":" + std::to_string(count) + ",\"indices\":{\"bufferView\":" + std::to_string(iv) +
             ",\"componentType\":" + std::to_string(indexType) + "},\"values\":{\"bufferView\":" + std::to_string(vv) + "}}}";
    }
    static std::string floats(const std::vector<Vec3>& p) {
        std::vector<float> flat;
        for (const Vec3& v : p) flat.insert(flat.end(), {v.x, v.y, v.z});
        return bytesOf(flat);
    }
    int positions(const std::vector<Vec3>& p) { return accessor(floats(p), kFloat, int(p.size()), "VEC3"); }
    int normals(const std::vector<Vec3>& n) { return positions(n); }
    int indices32(const std::vector<uint32_t>& i) { return accessor(bytesOf(i), kUInt, int(i.size()), "SCALAR"); }

    // A primitive's JSON: attributes POSITION (+ NORMAL), optional indices and material.
    static std::string primitive(int pos, int indices = -1, int mode = kTriangles, int material = -1, int normal = -1) {
        std::string s = "{\"attributes\":{\"POSITION\":" + std::to_string(pos);
        if (normal >= 0) s += ",\"NORMAL\":" + std::to_string(normal);
        s += "},\"mode\":" + std::to_string(mode);
        if (indices >= 0) s += ",\"indices\":" + std::to_string(indices);
        if (material >= 0) s += ",\"material\":" + std::to_string(material);
        return s + "}";
    }
    int mesh(const std::vector<std::string>& primitives) {
        meshes_.push_back("{\"primitives\":[" + join(primitives) + "]}");
        return int(meshes_.size()) - 1;
    }
    int material(const std::string& json) {
        materials_.push_back(json);
        return int(materials_.size()) - 1;
    }
    // `fields` is the node's JSON body without braces, e.g. "\"mesh\":0,\"translation\":[1,2,3]".
    // More top-level members, e.g. "\"textures\":[...],\"images\":[...]".
    void extra(const std::string& members) { extra_ = members; }
    int node(const std::string& fields, bool root = true) {
        nodes_.push_back("{" + fields + "}");
        int index = int(nodes_.size()) - 1;
        if (root) roots_.push_back(index);
        return index;
    }

    std::string json(const std::string& bufferUri) const {
        std::vector<std::string> roots;
        for (int r : roots_) roots.push_back(std::to_string(r));
        std::string s = "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[" + join(roots) + "]}]";
        s += ",\"nodes\":[" + join(nodes_) + "]";
        s += ",\"meshes\":[" + join(meshes_) + "]";
        if (!materials_.empty()) s += ",\"materials\":[" + join(materials_) + "]";
        s += ",\"accessors\":[" + join(accessors_) + "]";
        s += ",\"bufferViews\":[" + join(views_) + "]";
        s += ",\"buffers\":[{\"byteLength\":" + std::to_string(bin_.size()) + ",\"uri\":\"" + bufferUri + "\"}]";
        if (!extra_.empty()) s += "," + extra_;
        return s + "}";
    }
    // Writes `dir/name.gltf`, with the buffer as a base64 data URI or as `dir/name.bin`.
    std::string write(const TempDir& dir, const std::string& name, bool externalBin = false) const {
        std::string uri = "data:application/octet-stream;base64," + base64(bin_);
        if (externalBin) {
            uri = name + ".bin";
            writeFile(dir.file(uri), bin_);
        }
        std::string path = dir.file(name + ".gltf");
        writeFile(path, json(uri));
        return path;
    }

private:
    std::string bin_;
    std::vector<std::string> views_, accessors_, meshes_, materials_, nodes_;
    std::vector<int> roots_;
    std::string extra_;
};

// Unit cube [-0.5, 0.5]^3, 24 vertices, counter-clockwise seen from outside (as in make_scenes.py).
void unitCube(std::vector<Vec3>& pos, std::vector<Vec3>& nrm, std::vector<uint32_t>& idx) {
    for (int axis = 0; axis < 3; ++axis) {
        Vec3 e0(0.f), e1(0.f), e2(0.f);
        e0[axis] = 1.f;
        e1[(axis + 1) % 3] = 1.f;
        e2[(axis + 2) % 3] = 1.f;
        for (float sign : {1.f, -1.f}) {
            Vec3 c = 0.5f * sign * e0, u = 0.5f * e1, v = 0.5f * e2, n = sign * e0;
            if (glm::dot(glm::cross(u, v), n) < 0.f) std::swap(u, v);
            uint32_t base = uint32_t(pos.size());
            pos.insert(pos.end(), {c - u - v, c + u - v, c + u + v, c - u + v});
            nrm.insert(nrm.end(), 4, n);
            idx.insert(idx.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
        }
    }
}

// Triangle t of the scene as its three world positions.
std::vector<Vec3> triangle(const Scene& s, size_t t) {
    return {s.positions[3 * t], s.positions[3 * t + 1], s.positions[3 * t + 2]};
}

bool near(const Vec3& a, const Vec3& b, float eps = 1e-5f) { return glm::length(a - b) <= eps; }

// True when `tri` is `want` up to a cyclic rotation (same vertices, same winding).
bool sameTriangle(const std::vector<Vec3>& tri, const std::vector<Vec3>& want, float eps = 1e-5f) {
    for (int r = 0; r < 3; ++r)
        if (near(tri[0], want[r], eps) && near(tri[1], want[(r + 1) % 3], eps) && near(tri[2], want[(r + 2) % 3], eps))
            return true;
    return false;
}

::testing::AssertionResult trianglesAre(const Scene& s, const std::vector<std::vector<Vec3>>& want) {
    if (s.triangleCount() != want.size())
        return ::testing::AssertionFailure() << s.triangleCount() << " triangles, expected " << want.size();
    for (size_t t = 0; t < want.size(); ++t)
        if (!sameTriangle(triangle(s, t), want[t])) {
            std::ostringstream m;
            m << "triangle " << t << " is";
            for (const Vec3& p : triangle(s, t)) m << " (" << p.x << ", " << p.y << ", " << p.z << ")";
            m << ", expected";
            for (const Vec3& p : want[t]) m << " (" << p.x << ", " << p.y << ", " << p.z << ")";
            return ::testing::AssertionFailure() << m.str();
        }
    return ::testing::AssertionSuccess();
}

// Index of the material called `name`, or -1.
int materialNamed(const Scene& s, const std::string& name) {
    for (size_t m = 0; m < s.materials.size(); ++m)
        if (s.materials[m].name == name) return int(m);
    return -1;
}

// Triangles whose primitive came from the node called `node` (objectNames end in "(node i 'name')").
std::vector<size_t> trianglesOfNode(const Scene& s, const std::string& node) {
    std::vector<size_t> out;
    std::string suffix = "'" + node + "')";
    for (size_t t = 0; t < s.triangleCount(); ++t) {
        const std::string& o = s.objectNames[s.triObject[t]];
        if (o.size() >= suffix.size() && o.compare(o.size() - suffix.size(), suffix.size(), suffix) == 0) out.push_back(t);
    }
    return out;
}

Vec3 rotateY(const Vec3& v, float degrees) {
    float a = degrees * kPi / 180.f, c = std::cos(a), s = std::sin(a);
    return {c * v.x + s * v.z, v.y, -s * v.x + c * v.z};
}

// Every vertex of the node's triangles is one of the 8 corners of the box with this centre,
// half extents and rotation about +Y, and every corner is used.
void expectBox(const Scene& s, const std::string& node, Vec3 centre, Vec3 half, float yawDegrees) {
    std::vector<Vec3> corners;
    for (float x : {-1.f, 1.f})
        for (float y : {-1.f, 1.f})
            for (float z : {-1.f, 1.f}) corners.push_back(centre + rotateY(Vec3(x, y, z) * half, yawDegrees));
    std::vector<size_t> tris = trianglesOfNode(s, node);
    ASSERT_EQ(tris.size(), 12u) << node;
    std::set<int> used;
    for (size_t t : tris)
        for (const Vec3& p : triangle(s, t)) {
            int found = -1;
            for (size_t c = 0; c < corners.size(); ++c)
                if (near(p, corners[c], 1e-5f)) found = int(c);
            EXPECT_GE(found, 0) << node << " vertex (" << p.x << ", " << p.y << ", " << p.z << ") is no box corner";
            used.insert(found);
        }
    EXPECT_EQ(used.count(-1), 0u);
    EXPECT_EQ(used.size(), 8u) << node;
}

void expectInside(const Scene& s, Vec3 lo, Vec3 hi, float eps = 1e-5f) {
    for (const Vec3& p : s.positions)
        ASSERT_TRUE(p.x >= lo.x - eps && p.y >= lo.y - eps && p.z >= lo.z - eps && p.x <= hi.x + eps &&
                    p.y <= hi.y + eps && p.z <= hi.z + eps)
            << "(" << p.x << ", " << p.y << ", " << p.z << ") outside the expected bounds";
}

class RecordingReporter : public Reporter {
public:
    void warn(const std::string& m) override { warnings.push_back(m); }
    std::vector<std::string> warnings;
};

constexpr float kLightStrength = 25.f;
const Vec3 kLightRgb(1.f, 0.78f, 0.5f);

}  // namespace

// -- The generated scenes in data/ (expectations from scripts/make_scenes.py) -----------------

// Cornell box (.gltf + external .bin): 5 walls + light quad = 12 triangles, two 12-triangle cubes.
TEST(DataScenes, CornellBoxCountsMaterialsAndCamera) {
    Scene s = loadScene(dataPath("cornell_box.gltf"), silentReporter());
    EXPECT_EQ(s.triangleCount(), 36u);
    EXPECT_EQ(s.positions.size(), 3 * s.triangleCount());
    EXPECT_EQ(s.normals.size(), s.positions.size());
    EXPECT_EQ(s.uvs.size(), s.positions.size());
    EXPECT_TRUE(s.lights.empty());
    for (const char* name : {"white", "left_wall", "right_wall", "light"}) {
        int m = materialNamed(s, name);
        ASSERT_GE(m, 0) << name;
        EXPECT_EQ(s.materials[m].kind, MaterialKind::Lambert) << name;
    }
    EXPECT_TRUE(near(s.materials[materialNamed(s, "left_wall")].baseColor, Vec3(0.63f, 0.065f, 0.05f)));

    ASSERT_EQ(s.cameras.size(), 1u);
    Camera c = s.camera();
    EXPECT_TRUE(near(c.position, Vec3(0.f, 1.f, 3.4f))) << c.position.z;
    EXPECT_TRUE(near(c.forward, Vec3(0.f, 0.f, -1.f)));
    EXPECT_TRUE(near(c.up, Vec3(0.f, 1.f, 0.f)));
    EXPECT_TRUE(near(c.right, Vec3(1.f, 0.f, 0.f)));
    EXPECT_NEAR(c.yfov, 0.69f, 1e-6f);
    EXPECT_NEAR(c.aspect, 1.f, 1e-6f);
}

// The ceiling light: emissiveFactor (1, 0.78, 0.5) × emissiveStrength 25, a 0.5 × 0.4 m quad at
// y = 1.98 facing down, so it emits π·A·Le.
TEST(DataScenes, CornellLightIsEmissionTimesStrength) {
    Scene s = loadScene(dataPath("cornell_box.gltf"), silentReporter());
    int light = materialNamed(s, "light");
    ASSERT_GE(light, 0);
    EXPECT_TRUE(near(s.materials[light].emission, kLightRgb * kLightStrength, 1e-4f));
    float area = 0.f;
    int emissive = 0;
    for (size_t t = 0; t < s.triangleCount(); ++t) {
        if (!s.materials[s.triMaterial[t]].isEmissive()) continue;
        ++emissive;
        area += s.triangleArea(t);
        EXPECT_TRUE(near(s.geometricNormal(t), Vec3(0.f, -1.f, 0.f))) << "the light faces the floor";
        for (const Vec3& p : triangle(s, t)) EXPECT_NEAR(p.y, 1.98f, 1e-5f);
    }
    EXPECT_EQ(emissive, 2);
    EXPECT_NEAR(area, 0.2f, 1e-5f);
    Vec3 expected = kPi * 0.2f * kLightRgb * kLightStrength;
    EXPECT_TRUE(near(s.emittedPower(), expected, 1e-3f));
}

// The "boxes" parent translates by (0, 0, -0.1); its children's TRS put the tall box
// (0.6 × 1.2 × 0.6, yaw 17°) centred at (-0.35, 0.6, -0.3) and the short cube (0.6, yaw -18°) at
// (0.35, 0.3, 0.35): both stand on the floor y = 0.
TEST(DataScenes, CornellBoxesFlattenedWhereTheGeneratorPutsThem) {
    Scene s = loadScene(dataPath("cornell_box.gltf"), silentReporter());
    expectBox(s, "tall_box", Vec3(-0.35f, 0.6f, -0.3f), Vec3(0.3f, 0.6f, 0.3f), 17.f);
    expectBox(s, "short_box", Vec3(0.35f, 0.3f, 0.35f), Vec3(0.3f), -18.f);
    for (const char* box : {"tall_box", "short_box"}) {
        float minY = kInf;
        for (size_t t : trianglesOfNode(s, box))
            for (const Vec3& p : triangle(s, t)) minY = std::min(minY, p.y);
        EXPECT_NEAR(minY, 0.f, 1e-5f) << box << " sits on the floor";
    }
    // Walls' normals point into the room: the floor's up, the back wall's towards +z.
    for (size_t t : trianglesOfNode(s, "floor")) EXPECT_TRUE(near(s.geometricNormal(t), Vec3(0, 1, 0)));
    for (size_t t : trianglesOfNode(s, "back_wall")) EXPECT_TRUE(near(s.geometricNormal(t), Vec3(0, 0, 1)));
    // Cube faces point outward from the box centre.
    for (size_t t : trianglesOfNode(s, "tall_box")) {
        auto p = triangle(s, t);
        Vec3 centroid = (p[0] + p[1] + p[2]) / 3.f;
        EXPECT_GT(glm::dot(s.geometricNormal(t), centroid - Vec3(-0.35f, 0.6f, -0.3f)), 0.f);
    }
    expectInside(s, Vec3(-1, 0, -1), Vec3(1, 2, 1));
    EXPECT_TRUE(near(s.bounds.lo, Vec3(-1, 0, -1)) && near(s.bounds.hi, Vec3(1, 2, 1)));
}

// Glossy box (.glb): the room's 12 triangles, a 40 × 20 UV sphere (40·(2·20 − 2) = 1520 triangles,
// pole triangles skipped) and a 20-face icosahedron.
TEST(DataScenes, GlossyBoxGlbHasGlassSphereAndGlossyGold) {
    Scene s = loadScene(dataPath("glossy_box.glb"), silentReporter());
    EXPECT_EQ(s.triangleCount(), 1552u);
    int glass = materialNamed(s, "glass"), gold = materialNamed(s, "gold");
    ASSERT_GE(glass, 0);
    ASSERT_GE(gold, 0);
    EXPECT_EQ(s.materials[glass].kind, MaterialKind::Glass);
    EXPECT_NEAR(s.materials[glass].ior, 1.5f, 1e-6f);
    EXPECT_EQ(s.materials[gold].kind, MaterialKind::Glossy);
    EXPECT_NEAR(s.materials[gold].roughness, 0.3f, 1e-6f);
    EXPECT_NEAR(s.materials[gold].metallic, 1.f, 1e-6f);
    EXPECT_TRUE(near(s.materials[gold].baseColor, Vec3(1.f, 0.78f, 0.34f)));
    int glassKinds = 0, glossyKinds = 0;
    for (uint32_t m : std::set<uint32_t>(s.triMaterial.begin(), s.triMaterial.end())) {
        glassKinds += s.materials[m].kind == MaterialKind::Glass;
        glossyKinds += s.materials[m].kind == MaterialKind::Glossy;
    }
    EXPECT_EQ(glassKinds, 1);
    EXPECT_EQ(glossyKinds, 1);

    size_t glassTris = 0, goldTris = 0;
    float goldMinY = kInf;
    const Vec3 sphereCentre(-0.42f, 0.35f, 0.3f);
    for (size_t t = 0; t < s.triangleCount(); ++t) {
        if (int(s.triMaterial[t]) == glass) {
            ++glassTris;
            for (const Vec3& p : triangle(s, t)) EXPECT_NEAR(glm::length(p - sphereCentre), 0.35f, 1e-5f);
        } else if (int(s.triMaterial[t]) == gold) {
            ++goldTris;
            for (const Vec3& p : triangle(s, t)) goldMinY = std::min(goldMinY, p.y);
        }
    }
    EXPECT_EQ(glassTris, 1520u);
    EXPECT_EQ(goldTris, 20u);
    EXPECT_NEAR(goldMinY, 0.f, 1e-5f) << "one icosahedron face rests on the floor";
    expectInside(s, Vec3(-1, 0, -1), Vec3(1, 2, 1));
    EXPECT_TRUE(near(s.materials[materialNamed(s, "light")].emission, kLightRgb * kLightStrength, 1e-4f));
}

// direct_light.gltf (buffer as a data URI): a 6 × 6 m ground quad and four unit cubes
// = 2 + 4·12 = 50 triangles; one 40 W/sr point light at (0.5, 3, 0.5).
TEST(DataScenes, DirectLightDataUriPointLightAndCamera) {
    Scene s = loadScene(dataPath("direct_light.gltf"), silentReporter());
    EXPECT_EQ(s.triangleCount(), 50u);
    ASSERT_EQ(s.lights.size(), 1u);
    const PunctualLight& l = s.lights[0];
    EXPECT_EQ(l.type, LightType::Point);
    EXPECT_TRUE(near(l.position, Vec3(0.5f, 3.f, 0.5f)));
    EXPECT_TRUE(near(l.intensity, Vec3(40.f)));
    for (size_t t = 0; t < s.triangleCount(); ++t) EXPECT_FALSE(s.materials[s.triMaterial[t]].isEmissive());
    EXPECT_NEAR(s.emittedPower().x, 4.f * kPi * 40.f, 1e-2f);

    // Everything stands on the ground (y = 0); the highest point is the cap's top, 1.25 + 0.05.
    expectInside(s, Vec3(-3, 0, -3), Vec3(3, 1.3f, 3));
    EXPECT_NEAR(s.bounds.lo.y, 0.f, 1e-5f);
    EXPECT_NEAR(s.bounds.hi.y, 1.3f, 1e-5f);
    // The column (0.08 × 1.2 × 0.08) hangs under raised_block at (-0.4, 0, -1.2), yaw 20°.
    expectBox(s, "column", Vec3(-0.4f, 0.6f, -1.2f), Vec3(0.04f, 0.6f, 0.04f), 20.f);

    // The camera at (0, 4, 6) looks 40° down, straight towards -z.
    Camera c = s.camera();
    float a = 40.f * kPi / 180.f;
    EXPECT_TRUE(near(c.position, Vec3(0.f, 4.f, 6.f)));
    EXPECT_TRUE(near(c.forward, Vec3(0.f, -std::sin(a), -std::cos(a)), 1e-5f));
    EXPECT_TRUE(near(c.right, Vec3(1.f, 0.f, 0.f), 1e-5f));
    EXPECT_NEAR(c.aspect, 1.333f, 1e-5f);
}

// -- A scene from elsewhere ----------------------------------------------------------------------

// NVIDIA's nvpro Cornell box (Iray exporter): 16 732 triangles in the file, emissive ceiling
// panel with emissiveFactor [3, 3, 3], a 10 m room whose 5 cm thick walls reach ±5.05.
TEST(SharedScenes, NvproCornellBoxLoads) {
    const char* extra = std::getenv("RAYSPLAT_EXTRA_SCENES");
    if (!extra || !*extra) GTEST_SKIP() << "RAYSPLAT_EXTRA_SCENES (a folder of scenes from elsewhere) is not set";
    std::string path = (fs::path(extra) / "nvpro-cornellbox" / "cornellBox.gltf").string();
    if (!fs::exists(path)) GTEST_SKIP() << path << " is absent";
    Scene s = loadScene(path, silentReporter());
    EXPECT_GT(s.triangleCount(), 16000u);  // degenerate (zero-area) sphere pole triangles are dropped
    EXPECT_LE(s.triangleCount(), 16732u);
    size_t emissive = 0;
    for (size_t t = 0; t < s.triangleCount(); ++t)
        if (s.materials[s.triMaterial[t]].isEmissive()) {
            ++emissive;
            EXPECT_TRUE(near(s.materials[s.triMaterial[t]].emission, Vec3(3.f)));
        }
    EXPECT_GT(emissive, 0u);
    EXPECT_TRUE(isFinite(s.bounds.lo) && isFinite(s.bounds.hi));
    EXPECT_FALSE(s.bounds.empty());
    expectInside(s, Vec3(-5.06f), Vec3(5.06f));
    EXPECT_EQ(s.cameras.size(), 1u);
    EXPECT_TRUE(isFinite(s.emittedPower()));
    EXPECT_GT(s.emittedPower().x, 0.f);
}

// -- Emission --------------------------------------------------------------------------------

// A 2 × 3 m quad with emissiveFactor (0.5, 1, 0.25) × emissiveStrength 4: Le = (2, 4, 1), and a
// Lambertian emitter of one face radiates π·A·Le = π·6·Le. A non-emissive quad beside it adds nothing.
TEST(Emission, EmittedPowerIsPiAreaRadiance) {
    TempDir dir;
    GltfBuilder g;
    int quad = g.positions({{0, 0, 0}, {2, 0, 0}, {2, 3, 0}, {0, 3, 0}});
    int idx = g.indices32({0, 1, 2, 0, 2, 3});
    int other = g.positions({{5, 0, 0}, {6, 0, 0}, {6, 1, 0}});
    int lamp = g.material(
        "{\"name\":\"lamp\",\"emissiveFactor\":[0.5,1,0.25],"
        "\"extensions\":{\"KHR_materials_emissive_strength\":{\"emissiveStrength\":4}}}");
    int grey = g.material("{\"name\":\"grey\"}");
    g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(quad, idx, kTriangles, lamp),
                                                 GltfBuilder::primitive(other, -1, kTriangles, grey)})));
    Scene s = loadScene(g.write(dir, "lamp"), silentReporter());
    ASSERT_EQ(s.triangleCount(), 3u);
    const Vec3 le(2.f, 4.f, 1.f);
    EXPECT_TRUE(near(s.materials[lamp].emission, le));
    EXPECT_FALSE(s.materials[grey].isEmissive());
    Vec3 power = s.emittedPower();
    Vec3 expected = kPi * 6.f * le;
    EXPECT_NEAR(power.x, expected.x, 1e-4f * expected.x);
    EXPECT_NEAR(power.y, expected.y, 1e-4f * expected.y);
    EXPECT_NEAR(power.z, expected.z, 1e-4f * expected.z);
}

// -- Loader details on hand-made files ------------------------------------------------------------

// T(1,2,3) · R(90° about z) · S(2,1,1) takes (1,0,0) → (1,4,3), (0,1,0) → (0,2,3), (0,0,1) → (1,2,4).
// One node gives it as a column-major matrix, another as a parent translation over a child's
// rotation and scale: both must put the triangle there, winding kept (det = +2).
TEST(Loader, MatrixAndParentTrsGiveHandComputedWorldVertices) {
    TempDir dir;
    GltfBuilder g;
    int mesh = g.mesh({GltfBuilder::primitive(g.positions({{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}))});
    std::string m = std::to_string(mesh);
    g.node("\"name\":\"by_matrix\",\"mesh\":" + m + ",\"matrix\":[0,2,0,0, -1,0,0,0, 0,0,1,0, 1,2,3,1]");
    const float h = std::sqrt(0.5f);
    int child = g.node("\"name\":\"child\",\"mesh\":" + m + ",\"rotation\":[0,0," + std::to_string(h) + "," +
                           std::to_string(h) + "],\"scale\":[2,1,1]",
                       false);
    g.node("\"name\":\"parent\",\"translation\":[1,2,3],\"children\":[" + std::to_string(child) + "]");
    Scene s = loadScene(g.write(dir, "transforms"), silentReporter());
    std::vector<Vec3> want = {{1, 4, 3}, {0, 2, 3}, {1, 2, 4}};
    EXPECT_TRUE(trianglesAre(s, {want, want}));
    ASSERT_EQ(trianglesOfNode(s, "by_matrix").size(), 1u);
    ASSERT_EQ(trianglesOfNode(s, "child").size(), 1u);
}

// A node whose extras set raysplat_portal (Blender: an object's custom property) is a light
// portal: its triangles, in world space, go to Scene::portals and not into the geometry; false
// or 0 leaves the node geometry.
TEST(Loader, PortalNodesAreNotGeometry) {
    TempDir dir;
    GltfBuilder g;
    int mesh = g.mesh({GltfBuilder::primitive(g.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}))});
    std::string m = std::to_string(mesh);
    g.node("\"name\":\"wall\",\"mesh\":" + m);
    g.node("\"name\":\"window\",\"mesh\":" + m + ",\"translation\":[0,0,5],\"extras\":{\"raysplat_portal\":true}");
    g.node("\"name\":\"door\",\"mesh\":" + m + ",\"translation\":[0,0,7],\"extras\":{\"raysplat_portal\":1}");
    g.node("\"name\":\"not\",\"mesh\":" + m + ",\"translation\":[0,0,9],\"extras\":{\"raysplat_portal\":false}");
    Scene s = loadScene(g.write(dir, "portals"), silentReporter());
    EXPECT_EQ(s.triangleCount(), 2u);
    EXPECT_EQ(trianglesOfNode(s, "wall").size(), 1u);
    EXPECT_EQ(trianglesOfNode(s, "not").size(), 1u);
    ASSERT_EQ(s.portals.size(), 6u);
    EXPECT_EQ(s.portals[0], Vec3(0, 0, 5));
    EXPECT_EQ(s.portals[5], Vec3(0, 1, 7));
    EXPECT_EQ(s.objectNames.size(), 2u);
}

// The scene's extras carry its environment: raysplat_sky, or raysplat_env (a file beside the
// glTF) with its strength and rotation; a malformed value is an error naming the scene.
TEST(Loader, SceneExtrasGiveTheEnvironment) {
    TempDir dir;
    auto load = [&](const std::string& extras) {
        GltfBuilder g;
        g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(g.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}))})));
        std::string path = g.write(dir, "env");
        // Put the extras on scene 0.
        std::ifstream in(path);
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const std::string from = "\"scenes\":[{\"nodes\":[0]";
        text.replace(text.find(from), from.size(), from + ",\"extras\":{" + extras + "}");
        writeFile(path, text);
        return loadScene(path, silentReporter());
    };
    Scene sky = load("\"raysplat_sky\":[0.5,1,2]");
    EXPECT_EQ(sky.environment.sky, Vec3(0.5f, 1.f, 2.f));
    EXPECT_TRUE(sky.environment.file.empty());
    Scene env = load("\"raysplat_env\":\"sky.exr\",\"raysplat_env_strength\":3,\"raysplat_env_rotation\":90");
    EXPECT_EQ(env.environment.file, (dir.path() / "sky.exr").string());
    EXPECT_EQ(env.environment.strength, 3.f);
    EXPECT_EQ(env.environment.rotation, 90.f);
    try {
        load("\"raysplat_sky\":[1,-1,1]");
        FAIL() << "expected an Error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("scene 0"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("raysplat_sky"), std::string::npos) << e.what();
    }
}

// Without an indices accessor, vertices 3t..3t+2 form triangle t; a trailing partial triangle is dropped.
TEST(Loader, NonIndexedPrimitive) {
    TempDir dir;
    GltfBuilder g;
    std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {9, 9, 9}};
    g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(g.positions(p))})));
    Scene s = loadScene(g.write(dir, "nonindexed"), silentReporter());
    EXPECT_TRUE(trianglesAre(s, {{p[0], p[1], p[2]}, {p[3], p[4], p[5]}}));
}

// The same quad indexed with uint8, uint16 and uint32 indices (external .bin) gives the same
// two triangles; index values above 255 in the wide types read back intact.
TEST(Loader, IndexComponentTypes) {
    std::vector<Vec3> quad = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    std::vector<uint32_t> order = {0, 1, 2, 0, 2, 3};
    for (int type : {kUByte, kUShort, kUInt}) {
        SCOPED_TRACE("componentType " + std::to_string(type));
        TempDir dir;
        GltfBuilder g;
        // For the wide types, pad the vertex list so the quad lives at indices 300..303.
        uint32_t base = type == kUByte ? 0 : 300;
        std::vector<Vec3> pos(base, Vec3(7.f));
        pos.insert(pos.end(), quad.begin(), quad.end());
        int p = g.positions(pos);
        std::string bytes;
        for (uint32_t i : order) {
            uint32_t v = base + i;
            if (type == kUByte) bytes += char(uint8_t(v));
            else if (type == kUShort) { uint16_t u = uint16_t(v); bytes.append(reinterpret_cast<char*>(&u), 2); }
            else bytes.append(reinterpret_cast<char*>(&v), 4);
        }
        int idx = g.accessor(bytes, type, int(order.size()), "SCALAR");
        g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(p, idx)})));
        Scene s = loadScene(g.write(dir, "indices", /*externalBin=*/true), silentReporter());
        EXPECT_TRUE(trianglesAre(s, {{quad[0], quad[1], quad[2]}, {quad[0], quad[2], quad[3]}}));
    }
}

// glTF spec §3.7.2.1: strip triangle i is {v_i, v_i+(1+i%2), v_i+(2−i%2)}, fan triangle i is
// {v_i+1, v_i+2, v_0}. A zigzag strip and a fan in the z = 0 plane, all counter-clockwise seen
// from +z: every triangle's geometric normal must be +z.
TEST(Loader, TriangleStripsAndFans) {
    TempDir dir;
    GltfBuilder g;
    std::vector<Vec3> strip = {{0, 1, 0}, {0, 0, 0}, {1, 1, 0}, {1, 0, 0}, {2, 1, 0}};
    std::vector<Vec3> fan = {{0, 0, 5}, {1, 0, 5}, {1, 1, 5}, {0, 1, 5}, {-1, 1, 5}};
    int ps = g.positions(strip), pf = g.positions(fan);
    int is = g.indices32({0, 1, 2, 3, 4});
    g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(ps, is, kStrip),
                                                 GltfBuilder::primitive(pf, -1, kFan)})));
    Scene s = loadScene(g.write(dir, "strips"), silentReporter());
    EXPECT_TRUE(trianglesAre(s, {{strip[0], strip[1], strip[2]},
                                 {strip[1], strip[3], strip[2]},
                                 {strip[2], strip[3], strip[4]},
                                 {fan[1], fan[2], fan[0]},
                                 {fan[2], fan[3], fan[0]},
                                 {fan[3], fan[4], fan[0]}}));
    for (size_t t = 0; t < s.triangleCount(); ++t) EXPECT_TRUE(near(s.geometricNormal(t), Vec3(0, 0, 1))) << t;
}

// A closed cube wound counter-clockwise from outside, placed with scale (−1, 1, 1) (a mirror,
// det < 0) and, as a control, with scale (1, 1, 1): in both, every geometric normal and every
// shading normal must point away from the cube's centre.
TEST(Loader, MirroringScaleKeepsNormalsOutward) {
    TempDir dir;
    GltfBuilder g;
    std::vector<Vec3> pos, nrm;
    std::vector<uint32_t> idx;
    unitCube(pos, nrm, idx);
    int mesh = g.mesh({GltfBuilder::primitive(g.positions(pos), g.indices32(idx), kTriangles, -1, g.normals(nrm))});
    std::string m = std::to_string(mesh);
    g.node("\"name\":\"mirrored\",\"mesh\":" + m + ",\"translation\":[3,0,0],\"scale\":[-1,1,1]");
    g.node("\"name\":\"plain\",\"mesh\":" + m + ",\"translation\":[-3,0,0]");
    Scene s = loadScene(g.write(dir, "mirror"), silentReporter());
    ASSERT_EQ(s.triangleCount(), 24u);
    for (auto [node, centre] : {std::pair{"mirrored", Vec3(3, 0, 0)}, std::pair{"plain", Vec3(-3, 0, 0)}}) {
        std::vector<size_t> tris = trianglesOfNode(s, node);
        ASSERT_EQ(tris.size(), 12u) << node;
        for (size_t t : tris) {
            auto p = triangle(s, t);
            Vec3 out = glm::normalize((p[0] + p[1] + p[2]) / 3.f - centre);
            EXPECT_GT(glm::dot(s.geometricNormal(t), out), 0.5f) << node << " triangle " << t;
            for (int k = 0; k < 3; ++k)
                EXPECT_GT(glm::dot(s.normals[3 * t + k], out), 0.5f) << node << " shading normal, triangle " << t;
        }
    }
}

// A POINTS primitive is skipped with a warning naming the mesh and primitive; the mesh's
// triangle primitive still loads, and nothing throws.
TEST(Loader, PointsPrimitiveSkippedWithWarning) {
    TempDir dir;
    GltfBuilder g;
    int points = g.positions({{0, 0, 0}, {1, 1, 1}});
    int tri = g.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(points, -1, kPoints),
                                                 GltfBuilder::primitive(tri)})));
    RecordingReporter reporter;
    Scene s;
    std::string path = g.write(dir, "points");
    ASSERT_NO_THROW(s = loadScene(path, reporter));
    EXPECT_EQ(s.triangleCount(), 1u);
    ASSERT_EQ(reporter.warnings.size(), 1u);
    const std::string& w = reporter.warnings[0];
    EXPECT_NE(w.find("points.gltf"), std::string::npos) << w;
    EXPECT_NE(w.find("mesh 0"), std::string::npos) << w;
    EXPECT_NE(w.find("primitive 0"), std::string::npos) << w;
}

// A file whose only primitive is POINTS has nothing to render: an Error naming the file.
TEST(Loader, OnlyPointsIsAnErrorNamingTheFile) {
    TempDir dir;
    GltfBuilder g;
    g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(g.positions({{0, 0, 0}}), -1, kPoints)})));
    std::string path = g.write(dir, "only_points");
    RecordingReporter reporter;
    try {
        loadScene(path, reporter);
        FAIL() << "expected an Error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Scene);
        EXPECT_NE(std::string(e.what()).find("only_points.gltf"), std::string::npos) << e.what();
    }
    EXPECT_EQ(reporter.warnings.size(), 1u);
}

// A baseColorTexture whose image file is 0 bytes: tinygltf warns and leaves the image empty; the
// load fails with one Error naming the file and "image 0", and the failed load reports no
// warnings of its own (the CLI prints exactly one line).
// alphaMode and alphaCutoff, the base colour factor's alpha, and a texture's alpha channel (a
// 2 × 1 TGA, alpha 255 and 0, which the image decoder reads like a PNG): solidAt cuts the
// surface where factor × texel alpha < cutoff (MASK) and keeps it with probability alpha (BLEND).
TEST(Loader, AlphaModesAndTextureAlpha) {
    TempDir dir;
    GltfBuilder g;
    int leaf = g.material("{\"name\":\"leaf\",\"alphaMode\":\"MASK\",\"alphaCutoff\":0.3,"
                          "\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,0.5],\"baseColorTexture\":{\"index\":0}}}");
    int glass = g.material("{\"name\":\"veil\",\"alphaMode\":\"BLEND\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,0.25]}}");
    int positions = g.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    g.node("\"name\":\"leaf\",\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(positions, -1, kTriangles, leaf)})));
    g.node("\"name\":\"veil\",\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(positions, -1, kTriangles, glass)})));
    g.extra("\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"alpha.tga\"}]");
    std::string tga(18, '\0');
    tga[2] = 2;                        // uncompressed true colour
    tga[12] = 2, tga[14] = 1;          // 2 × 1
    tga[16] = 32, tga[17] = 0x28;      // 32 bits, 8 of alpha, top-left origin
    tga += std::string("\xff\xff\xff\xff\xff\xff\xff\x00", 8);  // BGRA: opaque, then transparent
    writeFile(dir.file("alpha.tga"), tga);
    Scene s = loadScene(g.write(dir, "alpha"), silentReporter());
    ASSERT_EQ(s.textures.size(), 1u);
    ASSERT_TRUE(s.textures[0].hasAlpha());
    ASSERT_EQ(s.textures[0].width() * s.textures[0].height(), 2);
    EXPECT_EQ(s.textures[0].alphaAt(0), 1.f);
    EXPECT_EQ(s.textures[0].alphaAt(1), 0.f);
    const Material& m = s.materials[size_t(leaf)];
    EXPECT_EQ(m.alphaMode, AlphaMode::Mask);
    EXPECT_FLOAT_EQ(m.alphaCutoff, 0.3f);
    EXPECT_FLOAT_EQ(m.opacity, 0.5f);
    EXPECT_EQ(s.materials[size_t(glass)].alphaMode, AlphaMode::Blend);
    EXPECT_TRUE(s.hasCutouts());
    // Triangle 0 (the leaf) has uvs (0, 0): texel 0, alpha 0.5 ≥ 0.3. Move them onto texel 1.
    EXPECT_TRUE(s.solidAt(0, 0.2f, 0.2f, 0.9f));
    for (int k = 0; k < 3; ++k) s.uvs[k] = Vec2(0.75f, 0.5f);
    EXPECT_FALSE(s.solidAt(0, 0.2f, 0.2f, 0.f));
    EXPECT_TRUE(s.solidAt(1, 0.2f, 0.2f, 0.2f));   // BLEND, alpha 0.25
    EXPECT_FALSE(s.solidAt(1, 0.2f, 0.2f, 0.3f));
}

TEST(Loader, EmptyTextureImageIsOneErrorNamingTheImage) {
    TempDir dir;
    GltfBuilder g;
    int painted = g.material("{\"name\":\"painted\",\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}");
    g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(g.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}),
                                                                        -1, kTriangles, painted)})));
    g.extra("\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"empty.png\"}]");
    writeFile(dir.file("empty.png"), "");
    std::string path = g.write(dir, "texture");

    RecordingReporter reporter;
    try {
        loadScene(path, reporter);
        FAIL() << "expected an Error";
    } catch (const Error& e) {
        std::string what = e.what();
        EXPECT_NE(what.find("texture.gltf"), std::string::npos) << what;
        EXPECT_NE(what.find("image 0"), std::string::npos) << what;
        EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
    EXPECT_TRUE(reporter.warnings.empty()) << reporter.warnings.front();
}

// -- Sparse accessors ---------------------------------------------------------------------------

namespace {

// A quad (0, 1, 2, 0, 2, 3) and a triangle, both emissive. Sparse: the quad's POSITION holds
// 9s at vertices 1 and 3 that uint16 sparse indices replace; its uint32 indices are zeros that
// uint8 sparse indices replace at 1, 2, 4, 5; the triangle's POSITION has no bufferView (zeros)
// and all three vertices come from uint32 sparse indices. Dense: the same, written out.
std::string quadAndTriangle(const TempDir& dir, bool sparse) {
    const std::vector<Vec3> quad = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, tri = {{2, 0, -1}, {3, 0, -1}, {2, 1, -1}};
    GltfBuilder g;
    const int glow = g.material("{\"emissiveFactor\":[1,0.5,0.25]}");
    std::vector<Vec3> base = quad;
    if (sparse) base[1] = base[3] = Vec3(9.f);
    const int p = g.positions(base);
    const int i = g.indices32(sparse ? std::vector<uint32_t>(6, 0) : std::vector<uint32_t>{0, 1, 2, 0, 2, 3});
    const int t = sparse ? g.zeros(kFloat, 3, "VEC3") : g.positions(tri);
    if (sparse) {
        g.sparse(p, 2, bytesOf(std::vector<uint16_t>{1, 3}), kUShort, GltfBuilder::floats({quad[1], quad[3]}));
        g.sparse(i, 4, std::string("\x01\x02\x04\x05", 4), kUByte, bytesOf(std::vector<uint32_t>{1, 2, 2, 3}));
        g.sparse(t, 3, bytesOf(std::vector<uint32_t>{0, 1, 2}), kUInt, GltfBuilder::floats(tri));
    }
    g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(p, i, kTriangles, glow),
                                                 GltfBuilder::primitive(t, -1, kTriangles, glow)})));
    return g.write(dir, sparse ? "sparse" : "dense");
}

}  // namespace

// The sparse file gives the hand-written triangles, and it loads and renders (path tracer,
// framing camera) to the bit as the file with the substitutions written out densely.
TEST(Loader, SparseAccessorsMatchTheirDenseEquivalent) {
    TempDir dir;
    const Scene sparse = loadScene(quadAndTriangle(dir, true), silentReporter());
    const Scene dense = loadScene(quadAndTriangle(dir, false), silentReporter());
    EXPECT_TRUE(trianglesAre(sparse, {{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, {{0, 0, 0}, {1, 1, 0}, {0, 1, 0}},
                                      {{2, 0, -1}, {3, 0, -1}, {2, 1, -1}}}));
    ASSERT_EQ(sparse.positions.size(), dense.positions.size());
    EXPECT_EQ(0, std::memcmp(sparse.positions.data(), dense.positions.data(), dense.positions.size() * sizeof(Vec3)));
    EXPECT_EQ(0, std::memcmp(sparse.normals.data(), dense.normals.data(), dense.normals.size() * sizeof(Vec3)));

    RenderConfig cfg;
    cfg.output = "unused.exr";
    cfg.method = Method::Path;
    cfg.width = cfg.height = 16;
    cfg.spp = 2;
    const RenderResult a = render(sparse, cfg, silentReporter()), b = render(dense, cfg, silentReporter());
    EXPECT_GT(rs::test::layerMean(a.film, kEmission), 0.0);
    for (int l = 0; l < kLayerCount; ++l)
        EXPECT_EQ(0, std::memcmp(a.film.layers[l].data(), b.film.layers[l].data(), a.film.pixelCount() * sizeof(Vec3)))
            << layerName(l);
}

// KHR_mesh_quantization: POSITION as shorts that are their values under a node scale of 1/1000,
// TEXCOORD_0 as unsigned shorts that are their values, NORMAL as normalized bytes: the triangle,
// normals and uvs of the float file. Without the extension the same integers are normalized (the
// core rule), so the positions differ.
TEST(Loader, QuantizedMeshesMatchTheirFloatEquivalent) {
    TempDir dir;
    auto write = [&](bool quantized, bool declared) {
        GltfBuilder g;
        int p, n, uv;
        if (quantized) {
            p = g.accessor(bytesOf(std::vector<int16_t>{0, 0, 0, 1000, 0, 0, 0, 1000, 0}), 5122, 3, "VEC3");
            n = g.accessor(std::string("\x00\x00\x7f\x00\x00\x7f\x00\x00\x7f", 9), 5120, 3, "VEC3", true);
            uv = g.accessor(bytesOf(std::vector<uint16_t>{0, 0, 2, 0, 0, 2}), kUShort, 3, "VEC2");
        } else {
            p = g.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
            n = g.normals({{0, 0, 1}, {0, 0, 1}, {0, 0, 1}});
            uv = g.accessor(bytesOf(std::vector<float>{0, 0, 2, 0, 0, 2}), kFloat, 3, "VEC2");
        }
        const std::string prim = "{\"attributes\":{\"POSITION\":" + std::to_string(p) + ",\"NORMAL\":" + std::to_string(n) +
                                 ",\"TEXCOORD_0\":" + std::to_string(uv) + "}}";
        g.node(std::string(quantized ? "\"scale\":[0.001,0.001,0.001]," : "") + "\"mesh\":" + std::to_string(g.mesh({prim})));
        if (declared) g.extra("\"extensionsUsed\":[\"KHR_mesh_quantization\"],\"extensionsRequired\":[\"KHR_mesh_quantization\"]");
        return g.write(dir, std::string(quantized ? "quantized" : "float") + (declared ? "_declared" : ""));
    };
    const Scene quantized = loadScene(write(true, true), silentReporter());
    const Scene plain = loadScene(write(false, false), silentReporter());
    ASSERT_EQ(quantized.positions.size(), plain.positions.size());
    for (size_t v = 0; v < plain.positions.size(); ++v) {
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(quantized.positions[v][k], plain.positions[v][k], 1e-6f) << "vertex " << v;
            EXPECT_NEAR(quantized.normals[v][k], plain.normals[v][k], 1e-6f) << "vertex " << v;
        }
        EXPECT_EQ(quantized.uvs[v], plain.uvs[v]) << "vertex " << v;
    }
    const Scene undeclared = loadScene(write(true, false), silentReporter());
    EXPECT_NEAR(undeclared.positions[1].x, 1000.f / 32767.f * 0.001f, 1e-9f);
}

// Bad sparse accessors are one Error naming the file and the accessor: an index past the base
// accessor's count, values that run past their bufferView, more substitutions than elements.
TEST(Loader, BadSparseAccessorsAreErrorsNamingTheAccessor) {
    const std::vector<Vec3> tri = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    struct Case {
        const char* name;
        int count;
        std::vector<uint16_t> indices;
        std::vector<Vec3> values;
        const char* says;
    };
    for (const Case& c : {Case{"index_past", 1, {3}, {Vec3(1.f)}, "index 3 is past its 3 elements"},
                          Case{"short_values", 2, {0, 1}, {Vec3(1.f)}, "reads past the end"},
                          Case{"too_many", 4, {0, 1, 2, 2}, {tri[0], tri[1], tri[2], tri[2]}, "substitutes 4 of its 3"}}) {
        SCOPED_TRACE(c.name);
        TempDir dir;
        GltfBuilder g;
        const int p = g.positions(tri);
        g.sparse(p, c.count, bytesOf(c.indices), kUShort, GltfBuilder::floats(c.values));
        g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(p)})));
        const std::string path = g.write(dir, c.name);
        RecordingReporter reporter;
        try {
            loadScene(path, reporter);
            ADD_FAILURE() << "expected an Error";
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_EQ(e.kind(), ErrorKind::Scene);
            EXPECT_NE(what.find(std::string(c.name) + ".gltf"), std::string::npos) << what;
            EXPECT_NE(what.find("accessor 0"), std::string::npos) << what;
            EXPECT_NE(what.find(c.says), std::string::npos) << what;
        }
        EXPECT_TRUE(reporter.warnings.empty());
    }
}

// -- Cameras ------------------------------------------------------------------------------------

namespace {

// A quad, an unnamed perspective camera on node "Front" and an orthographic camera "top view"
// (xmag 2, ymag 1) on node "Top", 5 m up and turned −90° about x to look down −y.
std::string twoCameras(const TempDir& dir, const std::string& orthographic = "\"xmag\":2,\"ymag\":1") {
    GltfBuilder g;
    g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(g.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}))})));
    g.node("\"name\":\"Front\",\"camera\":0,\"translation\":[0,0,5]");
    const float h = std::sqrt(0.5f);
    g.node("\"name\":\"Top\",\"camera\":1,\"translation\":[0,5,0],\"rotation\":[" + std::to_string(-h) + ",0,0," +
           std::to_string(h) + "]");
    g.extra("\"cameras\":[{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.5,\"znear\":0.1}},"
            "{\"name\":\"top view\",\"type\":\"orthographic\",\"orthographic\":{" + orthographic + ",\"znear\":0.1,\"zfar\":100}}]");
    return g.write(dir, "cameras");
}

}  // namespace

// Both cameras load in node order, with their node's name and projection; --camera's value
// picks one by the camera's name, its node's name or its index, and anything else is a Config
// error that lists them.
TEST(Loader, CamerasByNameNodeNameOrIndex) {
    TempDir dir;
    const Scene s = loadScene(twoCameras(dir), silentReporter());
    ASSERT_EQ(s.cameras.size(), 2u);
    EXPECT_EQ(s.cameras[0].name, "camera 0");
    EXPECT_EQ(s.cameras[0].node, "Front");
    EXPECT_EQ(s.cameras[0].projection, Projection::Perspective);
    const Camera& top = s.cameras[1];
    EXPECT_EQ(top.name, "top view");
    EXPECT_EQ(top.node, "Top");
    EXPECT_EQ(top.projection, Projection::Orthographic);
    EXPECT_FLOAT_EQ(top.ymag, 1.f);
    EXPECT_FLOAT_EQ(top.aspect, 2.f);
    EXPECT_TRUE(near(top.position, Vec3(0, 5, 0)));
    EXPECT_TRUE(near(top.forward, Vec3(0, -1, 0)));
    EXPECT_TRUE(near(top.up, Vec3(0, 0, -1)));
    for (const char* which : {"top view", "Top", "1"}) {
        const Camera c = s.camera(which);
        EXPECT_EQ(c.name, "top view") << which;
        EXPECT_EQ(c.projection, Projection::Orthographic) << which;
    }
    for (const char* which : {"camera 0", "Front", "0", ""}) EXPECT_EQ(s.camera(which).node, "Front") << which;
    for (const char* which : {"2", "Back", "-1", "01x"}) {
        try {
            s.camera(which);
            ADD_FAILURE() << which << ": expected an Error";
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_EQ(e.kind(), ErrorKind::Config);
            EXPECT_NE(what.find(std::string("'") + which + "'"), std::string::npos) << what;
            EXPECT_NE(what.find("1 'top view' on node 'Top'"), std::string::npos) << what;
        }
    }
}

// An orthographic camera whose xmag or ymag is zero or negative: an Error naming the camera.
TEST(Loader, OrthographicCameraWithoutExtentIsAnError) {
    for (const char* extent : {"\"xmag\":0,\"ymag\":1", "\"xmag\":1,\"ymag\":-1"}) {
        SCOPED_TRACE(extent);
        TempDir dir;
        try {
            loadScene(twoCameras(dir, extent), silentReporter());
            ADD_FAILURE() << "expected an Error";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("camera 1 'top view'"), std::string::npos) << e.what();
        }
    }
}

namespace {

// An emissive square of side 0.5 (x in [0, 0.5], y in [−0.25, 0.25]) at z = −d facing +z, seen
// by an orthographic camera at the origin looking down −z with xmag 1, ymag 0.5.
Scene squareBeforeOrthographicCamera(float d) {
    Scene s;
    const uint32_t glow = rs::test::addMaterial(s, MaterialKind::Lambert, Vec3(0.5f), Vec3(1.f, 0.5f, 0.25f));
    rs::test::addQuad(s, {0.f, -0.25f, -d}, {0.5f, -0.25f, -d}, {0.5f, 0.25f, -d}, {0.f, 0.25f, -d}, glow);
    Camera c;
    c.projection = Projection::Orthographic;
    c.ymag = 0.5f;
    c.aspect = 2.f;
    s.cameras.push_back(c);
    s.computeBounds();
    return s;
}

}  // namespace

// Parallel rays: the square's image is the same at 1, 4 and 16 m, for the path tracer and the
// splat renderer, and it covers s / (2·xmag) · width = 0.5 / 2 · 32 = 8 columns (16 to 23) and
// s / (2·ymag) · height = 8 rows (4 to 11) of the 32 × 16 image (its height from xmag / ymag).
// A pinhole camera's image would shrink 16-fold over these distances.
TEST(Camera, OrthographicImageOfASquareIsTheSameAtAnyDistance) {
    for (Method method : {Method::Path, Method::Splat}) {
        SCOPED_TRACE(methodName(method));
        RenderConfig cfg;
        cfg.output = "unused.exr";
        cfg.method = method;
        cfg.width = 32;
        cfg.height = 0;
        cfg.photons = 1000;
        cfg.passes = 1;
        std::vector<Vec3> first;
        for (float d : {1.f, 4.f, 16.f}) {
            SCOPED_TRACE("d = " + std::to_string(d));
            const RenderResult r = render(squareBeforeOrthographicCamera(d), cfg, silentReporter());
            ASSERT_EQ(r.film.width, 32);
            ASSERT_EQ(r.film.height, 16);
            const std::vector<Vec3> image = r.film.beautyImage();
            int lit = 0;
            for (int y = 0; y < 16; ++y)
                for (int x = 0; x < 32; ++x) {
                    const Vec3 v = image[size_t(y) * 32 + x];
                    const bool inside = x >= 16 && x < 24 && y >= 4 && y < 12;
                    EXPECT_TRUE(near(v, inside ? Vec3(1.f, 0.5f, 0.25f) : Vec3(0.f), 1e-4f))
                        << "pixel " << x << "," << y << ": " << v.x << " " << v.y << " " << v.z;
                    lit += v.x > 0.5f;
                }
            EXPECT_EQ(lit, 64);
            if (first.empty()) first = image;
            else EXPECT_EQ(0, std::memcmp(first.data(), image.data(), image.size() * sizeof(Vec3)));
        }
    }
}

namespace {

// A PNG file of w × h pixels with `channels` (1 grey, 2 grey + alpha, 3 RGB, 4 RGBA) of `bits`
// (8 or 16) bits, pixel values v(x, y, channel), written here with zlib.
std::string pngFile(int w, int h, int channels, int bits, unsigned (*v)(int, int, int)) {
    auto be32 = [](uint32_t x) { return std::string{char(x >> 24), char(x >> 16), char(x >> 8), char(x)}; };
    auto chunk = [&](const std::string& type, const std::string& data) {
        const std::string body = type + data;
        return be32(uint32_t(data.size())) + body +
               be32(uint32_t(crc32(0, reinterpret_cast<const Bytef*>(body.data()), uInt(body.size()))));
    };
    std::string raw;
    for (int y = 0; y < h; ++y) {
        raw += '\0';  // filter: none
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < channels; ++c) {
                if (bits == 16) raw += char(v(x, y, c) >> 8);
                raw += char(v(x, y, c) & 255u);
            }
    }
    uLongf size = compressBound(uLong(raw.size()));
    std::string packed(size, '\0');
    compress(reinterpret_cast<Bytef*>(packed.data()), &size, reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size()));
    packed.resize(size);
    const char colourType[] = {0, 0, 4, 2, 6};
    const std::string ihdr = be32(uint32_t(w)) + be32(uint32_t(h)) + char(bits) + colourType[channels] + std::string(3, '\0');
    return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) + chunk("IDAT", packed) + chunk("IEND", "");
}

unsigned wideValue(int x, int y, int c) { return unsigned(x * 13001 + y * 7919 + c * 20011) % 65536u; }
unsigned greyAlphaValue(int x, int y, int c) { return c == 0 ? unsigned(x * 60 + y) : unsigned(y * 80); }

}  // namespace

// Three PNG textures (16-bit RGB, 8-bit grey + alpha, 8-bit RGBA): decoded on one thread and on
// three, every texel is the same; the 16-bit image keeps its 16 bits (8 bytes a texel, values
// v / 65535 through the sRGB formula); grey is expanded to RGB and keeps its alpha.
TEST(Loader, ImagesDecodeAlikeOnAnyThreadCountAndSixteenBitsStay) {
    TempDir dir;
    GltfBuilder g;
    std::vector<std::string> primitives;
    const int positions = g.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    for (int i = 0; i < 3; ++i)
        primitives.push_back(GltfBuilder::primitive(positions, -1, kTriangles, g.material(
            "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":" + std::to_string(i) + "}}}")));
    g.node("\"mesh\":" + std::to_string(g.mesh(primitives)));
    g.extra("\"textures\":[{\"source\":0},{\"source\":1},{\"source\":2}],"
            "\"images\":[{\"uri\":\"wide.png\"},{\"uri\":\"grey.png\"},{\"uri\":\"rgba.png\"}]");
    writeFile(dir.file("wide.png"), pngFile(5, 3, 3, 16, wideValue));
    writeFile(dir.file("grey.png"), pngFile(4, 4, 2, 8, greyAlphaValue));
    writeFile(dir.file("rgba.png"), pngFile(3, 2, 4, 8, [](int x, int y, int c) { return unsigned(x * 90 + y * 40 + c * 20); }));
    const std::string path = g.write(dir, "images");
    const Scene one = loadScene(path, silentReporter(), 1), three = loadScene(path, silentReporter(), 3);
    ASSERT_EQ(one.textures.size(), 3u);
    ASSERT_EQ(three.textures.size(), 3u);
    for (size_t t = 0; t < 3; ++t)
        for (int l = 0; l < one.textures[t].levelCount(); ++l)
            for (int y = 0; y < one.textures[t].levelHeight(l); ++y)
                for (int x = 0; x < one.textures[t].levelWidth(l); ++x)
                    ASSERT_EQ(one.textures[t].texel(l, x, y), three.textures[t].texel(l, x, y)) << t << " " << l;

    const Texture& wide = one.textures[0];
    EXPECT_TRUE(wide.sixteenBit());
    EXPECT_FALSE(wide.hasAlpha());
    EXPECT_EQ(wide.bytes(), 8u * (15 + 2 + 1));  // 5×3, 2×1, 1×1
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 5; ++x)
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(wide.texel(0, x, y)[c], std::pow((wideValue(x, y, c) / 65535.0 + 0.055) / 1.055, 2.4) *
                                                        (wideValue(x, y, c) / 65535.0 > 0.04045) +
                                                        (wideValue(x, y, c) / 65535.0 <= 0.04045) * wideValue(x, y, c) / 65535.0 / 12.92,
                            1e-5);
    const Texture& grey = one.textures[1];
    EXPECT_FALSE(grey.sixteenBit());
    EXPECT_TRUE(grey.hasAlpha());
    EXPECT_EQ(grey.bytes(), 4u * (16 + 4 + 1));
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) {
            const Vec4 t = grey.texel(0, x, y);
            EXPECT_EQ(t.x, t.z);
            EXPECT_EQ(t.w, float(greyAlphaValue(x, y, 1)) / 255.f);
            EXPECT_EQ(grey.alphaAt(y * 4 + x), t.w);
        }
}

// A JPEG texture (written by stb_image_write at quality 100, one colour): read as 8-bit sRGB
// without alpha, every texel within two codes of the colour written.
TEST(Loader, JpegTexture) {
    TempDir dir;
    GltfBuilder g;
    const int painted = g.material("{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}");
    g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(g.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}),
                                                                        -1, kTriangles, painted)})));
    g.extra("\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"wall.jpg\"}]");
    const uint8_t colour[3] = {200, 100, 50};
    std::vector<uint8_t> rgb(16 * 16 * 3);
    for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = colour[i % 3];
    std::string jpeg;
    stbi_write_jpg_to_func([](void* out, void* data, int size) { static_cast<std::string*>(out)->append(static_cast<char*>(data), size_t(size)); },
                           &jpeg, 16, 16, 3, rgb.data(), 100);
    ASSERT_GT(jpeg.size(), 100u);
    writeFile(dir.file("wall.jpg"), jpeg);
    const Scene s = loadScene(g.write(dir, "jpeg"), silentReporter());
    ASSERT_EQ(s.textures.size(), 1u);
    const Texture& t = s.textures[0];
    EXPECT_EQ(t.width(), 16);
    EXPECT_FALSE(t.sixteenBit());
    EXPECT_FALSE(t.hasAlpha());
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) {
                const float v = t.texel(0, x, y)[c];
                EXPECT_GE(v, srgbToLinear((colour[c] - 2) / 255.f)) << x << "," << y << "," << c;
                EXPECT_LE(v, srgbToLinear((colour[c] + 2) / 255.f)) << x << "," << y << "," << c;
            }
}

// An image in a bufferView (as in a .glb) reads as the same image in a file beside the glTF.
TEST(Loader, ImageInABufferViewReadsAsTheFile) {
    TempDir dir;
    const std::string png = pngFile(4, 4, 4, 8, [](int x, int y, int c) { return unsigned(x * 50 + y * 13 + c * 7); });
    writeFile(dir.file("rgba.png"), png);
    auto sceneWith = [&](bool inBuffer) {
        GltfBuilder g;
        const int painted = g.material("{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}");
        g.node("\"mesh\":" + std::to_string(g.mesh({GltfBuilder::primitive(g.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}),
                                                                            -1, kTriangles, painted)})));
        // The builder makes a bufferView with each accessor: the image uses the PNG's.
        const int view = inBuffer ? g.accessor(png, kUByte, int(png.size()), "SCALAR") : -1;
        g.extra("\"textures\":[{\"source\":0}],\"images\":[" +
                (inBuffer ? "{\"bufferView\":" + std::to_string(view) + ",\"mimeType\":\"image/png\"}" : std::string("{\"uri\":\"rgba.png\"}")) + "]");
        return loadScene(g.write(dir, inBuffer ? "in_buffer" : "in_file"), silentReporter());
    };
    const Scene file = sceneWith(false), buffer = sceneWith(true);
    ASSERT_EQ(buffer.textures.size(), 1u);
    ASSERT_EQ(buffer.textures[0].width(), 4);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) EXPECT_EQ(buffer.textures[0].texel(0, x, y), file.textures[0].texel(0, x, y));
}

// Every texture slot of the metallic-roughness model, KHR_texture_transform (its texCoord
// overriding the slot's), TEXCOORD_1, COLOR_0 as normalized bytes and TANGENT under a mirroring
// node: the colour slots read the image decoded from sRGB, the data slots (metallic-roughness,
// normal) read it as it is — two textures from one image; the tangent turns with the node and,
// mirrored, its bitangent's side flips.
TEST(Loader, TextureSlotsTransformsColoursAndTangents) {
    TempDir dir;
    GltfBuilder g;
    const std::string transform = "\"extensions\":{\"KHR_texture_transform\":{\"offset\":[0.25,0],\"scale\":[2,2],\"texCoord\":1}}";
    int mat = g.material("{\"name\":\"all\",\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0," + transform +
                         "},\"metallicRoughnessTexture\":{\"index\":0}},\"normalTexture\":{\"index\":0,\"scale\":0.5},"
                         "\"emissiveTexture\":{\"index\":0},\"emissiveFactor\":[1,1,1]}");
    int positions = g.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    int normals = g.normals({{0, 0, 1}, {0, 0, 1}, {0, 0, 1}});
    int uv0 = g.accessor(bytesOf(std::vector<float>{0, 0, 1, 0, 0, 1}), kFloat, 3, "VEC2");
    int uv1 = g.accessor(bytesOf(std::vector<float>{0.5f, 0.5f, 0.75f, 0.5f, 0.5f, 0.75f}), kFloat, 3, "VEC2");
    int color = g.accessor(std::string("\xff\x00\x80\x33\x66\x99\x00\x00\xff", 9), kUByte, 3, "VEC3");
    int tangent = g.accessor(bytesOf(std::vector<float>{1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1}), kFloat, 3, "VEC4");
    const std::string prim = "{\"attributes\":{\"POSITION\":" + std::to_string(positions) + ",\"NORMAL\":" + std::to_string(normals) +
                             ",\"TEXCOORD_0\":" + std::to_string(uv0) + ",\"TEXCOORD_1\":" + std::to_string(uv1) +
                             ",\"COLOR_0\":" + std::to_string(color) + ",\"TANGENT\":" + std::to_string(tangent) +
                             "},\"material\":" + std::to_string(mat) + "}";
    g.node("\"name\":\"mirrored\",\"scale\":[-1,1,1],\"mesh\":" + std::to_string(g.mesh({prim})));
    g.extra("\"extensionsUsed\":[\"KHR_texture_transform\"],\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"grey.tga\"}]");
    std::string tga(18, '\0');
    tga[2] = 2, tga[12] = 1, tga[14] = 1, tga[16] = 24, tga[17] = 0x20;  // 1 × 1, BGR
    tga += std::string("\x40\x80\xc0", 3);
    writeFile(dir.file("grey.tga"), tga);
    RecordingReporter reporter;
    Scene s = loadScene(g.write(dir, "slots"), reporter);
    EXPECT_TRUE(reporter.warnings.empty()) << reporter.warnings.front();

    const Material& m = s.materials[size_t(mat)];
    ASSERT_TRUE(m.baseColorTexture.present() && m.metallicRoughnessTexture.present() && m.normalTexture.present() &&
                m.emissiveTexture.present());
    EXPECT_EQ(s.textures.size(), 2u);
    EXPECT_EQ(m.baseColorTexture.texture, m.emissiveTexture.texture);
    EXPECT_EQ(m.metallicRoughnessTexture.texture, m.normalTexture.texture);
    const Vec4 srgb = s.textures[size_t(m.baseColorTexture.texture)].sample(Vec2(0.5f));
    const Vec4 linear = s.textures[size_t(m.normalTexture.texture)].sample(Vec2(0.5f));
    EXPECT_NEAR(linear.x, 192.f / 255.f, 1e-6f);  // TGA stores BGR
    EXPECT_NEAR(linear.z, 64.f / 255.f, 1e-6f);
    EXPECT_NEAR(srgb.x, std::pow((192.f / 255.f + 0.055f) / 1.055f, 2.4f), 1e-5f);
    EXPECT_EQ(m.kind, MaterialKind::Mix);  // metallic and roughness vary over the surface
    EXPECT_FLOAT_EQ(m.normalScale, 0.5f);
    EXPECT_EQ(m.baseColorTexture.texCoord, 1);
    EXPECT_EQ(m.metallicRoughnessTexture.texCoord, 0);
    EXPECT_EQ(m.baseColorTexture.transform.offset, Vec2(0.25f, 0.f));
    EXPECT_EQ(m.baseColorTexture.transform.scale, Vec2(2.f));

    // The mirror swaps corners 1 and 2 of the triangle; find corners by their TEXCOORD_0.
    ASSERT_EQ(s.triangleCount(), 1u);
    ASSERT_EQ(s.uvs1.size(), 3u);
    ASSERT_EQ(s.colors.size(), 3u);
    ASSERT_EQ(s.tangents.size(), 3u);
    for (int c = 0; c < 3; ++c) {
        const int v = s.uvs[c] == Vec2(0, 0) ? 0 : s.uvs[c] == Vec2(1, 0) ? 1 : 2;
        const Vec2 wantUv1[3] = {{0.5f, 0.5f}, {0.75f, 0.5f}, {0.5f, 0.75f}};
        const Vec4 wantColor[3] = {{1.f, 0.f, 128.f / 255.f, 1.f}, {0x33 / 255.f, 0x66 / 255.f, 0x99 / 255.f, 1.f}, {0, 0, 1, 1}};
        EXPECT_EQ(s.uvs1[c], wantUv1[v]) << "corner " << c;
        EXPECT_LT(glm::length(s.colors[c] - wantColor[v]), 1e-6f) << "corner " << c;
        EXPECT_EQ(s.tangents[c], Vec4(-1, 0, 0, -1)) << "corner " << c;
    }
}
