// glTF 2.0 → Scene (docs/design.md §3), through tinygltf (Debian's compiled library: no
// TINYGLTF_IMPLEMENTATION here). Takes a .gltf or .glb path; returns world-space triangles,
// materials mapped by the table of docs/design.md §3, KHR_lights_punctual lights and cameras.
// Every error names the file and the glTF object it was found in; nothing is dropped
// silently: non-triangle primitives are skipped with a warning.
#include "scene/scene.h"

#include <tiny_gltf.h>

#include <cstring>
#include <filesystem>
#include <functional>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <map>
#include <set>

#include "core/error.h"
#include "core/log.h"

namespace rs {

const char* materialKindName(MaterialKind kind) {
    switch (kind) {
        case MaterialKind::Lambert: return "lambert";
        case MaterialKind::Glossy: return "glossy";
        case MaterialKind::Mix: return "mix";
        case MaterialKind::Glass: return "glass";
        case MaterialKind::Mirror: return "mirror";
    }
    return "?";
}

namespace {

const std::set<std::string> kSupportedExtensions = {
    "KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_transmission",
    "KHR_materials_ior"};

std::string firstLine(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    size_t nl = s.find('\n');
    return nl == std::string::npos ? s : s.substr(0, nl);
}

std::string quoted(const std::string& kind, int index, const std::string& name) {
    std::string s = kind + " " + std::to_string(index);
    if (!name.empty()) s += " '" + name + "'";
    return s;
}

float srgbToLinear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

double extNumber(const tinygltf::ExtensionMap& ext, const char* extension, const char* key,
                 double fallback) {
    auto it = ext.find(extension);
    if (it == ext.end() || !it->second.Has(key)) return fallback;
    const tinygltf::Value& v = it->second.Get(key);
    return v.IsNumber() ? v.GetNumberAsDouble() : fallback;
}

class Loader {
public:
    Loader(const std::string& path, Reporter& reporter) : path_(path), reporter_(reporter) {}

    Scene load() {
        readFile();
        checkExtensions();
        scene_.path = path_;
        loadMaterials();
        loadLights();

        // Flatten the node hierarchy of the default scene into world space.
        if (model_.scenes.empty()) fail("the file has no scene");
        int sceneIndex = model_.defaultScene >= 0 ? model_.defaultScene : 0;
        if (sceneIndex >= int(model_.scenes.size())) fail("'scene' " + std::to_string(sceneIndex) + " does not exist");
        for (int root : model_.scenes[sceneIndex].nodes) visitNode(root, Mat4(1.f), 0);

        if (scene_.triangleCount() == 0) fail("the scene has no triangles");
        scene_.computeBounds();
        // tinygltf's warning only once the load succeeded: a failed load is one error line.
        if (!gltfWarning_.empty()) reporter_.warn(path_ + ": " + gltfWarning_);
        return std::move(scene_);
    }

private:
    [[noreturn]] void fail(const std::string& what, ErrorKind kind = ErrorKind::Scene) const {
        throw Error(kind, path_ + ": " + what);
    }

    void readFile() {
        std::error_code ec;
        if (!std::filesystem::exists(path_, ec)) fail("no such file", ErrorKind::Io);
        if (std::filesystem::is_directory(path_, ec)) fail("is a directory, not a glTF file", ErrorKind::Io);
        tinygltf::TinyGLTF gltf;
        std::string err, warn;
        std::string ext = std::filesystem::path(path_).extension().string();
        for (char& c : ext) c = char(std::tolower(c));
        bool ok = ext == ".glb" ? gltf.LoadBinaryFromFile(&model_, &err, &warn, path_)
                                : gltf.LoadASCIIFromFile(&model_, &err, &warn, path_);
        if (!ok) fail("cannot load glTF: " + firstLine(err.empty() ? "unknown error" : err));
        if (!warn.empty()) gltfWarning_ = firstLine(warn);
    }

    void checkExtensions() {
        for (const std::string& e : model_.extensionsRequired)
            if (!kSupportedExtensions.count(e))
                fail("required extension '" + e + "' is not supported");
    }

    // -- Materials (docs/design.md §3 table) ---------------------------------------------------
    void loadMaterials() {
        for (size_t i = 0; i < model_.materials.size(); ++i) {
            const tinygltf::Material& m = model_.materials[i];
            const auto& pbr = m.pbrMetallicRoughness;
            Material out;
            out.name = m.name.empty() ? "material " + std::to_string(i) : m.name;
            std::string where = quoted("material", int(i), m.name);
            for (int c = 0; c < 3; ++c) out.baseColor[c] = float(pbr.baseColorFactor.at(c));
            out.metallic = std::clamp(float(pbr.metallicFactor), 0.f, 1.f);
            out.roughness = std::clamp(float(pbr.roughnessFactor), 0.f, 1.f);
            float strength = float(extNumber(m.extensions, "KHR_materials_emissive_strength", "emissiveStrength", 1.0));
            for (int c = 0; c < 3; ++c) out.emission[c] = float(m.emissiveFactor.at(c)) * strength;
            float transmission = float(extNumber(m.extensions, "KHR_materials_transmission", "transmissionFactor", 0.0));
            out.ior = float(extNumber(m.extensions, "KHR_materials_ior", "ior", 1.5));
            if (!isFinite(out.baseColor) || !isFinite(out.emission) || !std::isfinite(out.metallic) ||
                !std::isfinite(out.roughness) || !(out.ior >= 1.0f && out.ior < 10.f))
                fail(where + " has a non-finite or out-of-range factor");
            if (glm::any(glm::lessThan(out.emission, Vec3(0.f)))) fail(where + " has negative emission");
            if (pbr.baseColorTexture.index >= 0)
                out.baseColorTexture = loadTexture(pbr.baseColorTexture.index, where);
            if (m.emissiveTexture.index >= 0)
                reporter_.warn(path_ + ": " + where + ": emissiveTexture is ignored (emissiveFactor used)");

            if (transmission > 0.f) {
                if (transmission < 1.f)
                    reporter_.warn(path_ + ": " + where + ": transmission " + std::to_string(transmission) +
                                   " treated as " + (transmission >= 0.5f ? "1" : "0"));
            }
            if (transmission >= 0.5f) out.kind = MaterialKind::Glass;
            else if (out.metallic >= 1.f) out.kind = out.roughness < 0.05f ? MaterialKind::Mirror : MaterialKind::Glossy;
            else if (out.metallic <= 0.f && out.roughness >= 1.f) out.kind = MaterialKind::Lambert;
            else out.kind = MaterialKind::Mix;
            scene_.materials.push_back(out);
        }
        // Primitives without a material use glTF's default: white-ish, metallic 1, roughness 1
        // per the spec's factor defaults; a renderer user expects a grey diffuse instead.
        defaultMaterial_ = uint32_t(scene_.materials.size());
        Material fallback;
        fallback.name = "default";
        scene_.materials.push_back(fallback);
    }

    int loadTexture(int textureIndex, const std::string& where) {
        if (textureIndex >= int(model_.textures.size()))
            fail(where + ": texture " + std::to_string(textureIndex) + " does not exist");
        int source = model_.textures[textureIndex].source;
        if (source < 0 || source >= int(model_.images.size()))
            fail(quoted("texture", textureIndex, model_.textures[textureIndex].name) + " has no valid image source");
        auto cached = textureOfImage_.find(source);
        if (cached != textureOfImage_.end()) return cached->second;

        const tinygltf::Image& img = model_.images[source];
        std::string iwhere = quoted("image", source, img.name.empty() ? img.uri : img.name);
        if (img.width <= 0 || img.height <= 0 || img.image.empty()) fail(iwhere + " has zero size");
        int bytesPer = img.bits / 8;
        if ((img.bits != 8 && img.bits != 16) || img.component < 1 || img.component > 4 ||
            img.image.size() < size_t(img.width) * img.height * img.component * bytesPer)
            fail(iwhere + " has an unsupported pixel format");
        Texture tex;
        tex.name = iwhere;
        tex.width = img.width;
        tex.height = img.height;
        tex.texels.resize(size_t(img.width) * img.height);
        float maxValue = img.bits == 8 ? 255.f : 65535.f;
        for (size_t p = 0; p < tex.texels.size(); ++p) {
            float ch[4];
            for (int c = 0; c < img.component; ++c) {
                size_t at = (p * img.component + c) * bytesPer;
                unsigned v = bytesPer == 1 ? img.image[at] : unsigned(img.image[at] | (img.image[at + 1] << 8));
                ch[c] = float(v) / maxValue;
            }
            Vec3 rgb = img.component >= 3 ? Vec3(ch[0], ch[1], ch[2]) : Vec3(ch[0]);
            tex.texels[p] = Vec3(srgbToLinear(rgb.x), srgbToLinear(rgb.y), srgbToLinear(rgb.z));
        }
        int index = int(scene_.textures.size());
        scene_.textures.push_back(std::move(tex));
        textureOfImage_[source] = index;
        return index;
    }

    // -- KHR_lights_punctual -----------------------------------------------------------
    void loadLights() {
        for (size_t i = 0; i < model_.lights.size(); ++i) {
            const tinygltf::Light& l = model_.lights[i];
            std::string where = quoted("light", int(i), l.name);
            PunctualLight out;
            out.name = l.name.empty() ? "light " + std::to_string(i) : l.name;
            Vec3 color(1.f);
            if (l.color.size() == 3) color = Vec3(float(l.color[0]), float(l.color[1]), float(l.color[2]));
            out.intensity = color * float(l.intensity);
            if (!isFinite(out.intensity) || glm::any(glm::lessThan(out.intensity, Vec3(0.f))))
                fail(where + " has a non-finite or negative intensity");
            if (l.type == "point") out.type = LightType::Point;
            else if (l.type == "spot") {
                out.type = LightType::Spot;
                out.cosInner = std::cos(float(l.spot.innerConeAngle));
                out.cosOuter = std::cos(float(l.spot.outerConeAngle));
                if (!(out.cosInner > out.cosOuter)) fail(where + ": spot innerConeAngle must be below outerConeAngle");
            } else if (l.type == "directional") out.type = LightType::Directional;
            else fail(where + " has unknown type '" + l.type + "'");
            lightTemplates_.push_back(out);
        }
    }

    // -- Node hierarchy ----------------------------------------------------------------
    void visitNode(int index, const Mat4& parent, int depth) {
        if (index < 0 || index >= int(model_.nodes.size()))
            fail("node " + std::to_string(index) + " does not exist");
        if (depth > 256) fail(quoted("node", index, model_.nodes[index].name) + ": node hierarchy has a cycle");
        const tinygltf::Node& node = model_.nodes[index];
        std::string where = quoted("node", index, node.name);

        Mat4 local(1.f);
        if (node.matrix.size() == 16) {
            for (int k = 0; k < 16; ++k) glm::value_ptr(local)[k] = float(node.matrix[k]);
        } else {
            Mat4 t(1.f), r(1.f), s(1.f);
            if (node.translation.size() == 3)
                t = glm::translate(Mat4(1.f), Vec3(node.translation[0], node.translation[1], node.translation[2]));
            if (node.rotation.size() == 4)
                r = glm::mat4_cast(glm::normalize(glm::quat(float(node.rotation[3]), float(node.rotation[0]),
                                                            float(node.rotation[1]), float(node.rotation[2]))));
            if (node.scale.size() == 3) s = glm::scale(Mat4(1.f), Vec3(node.scale[0], node.scale[1], node.scale[2]));
            local = t * r * s;
        }
        Mat4 world = parent * local;
        for (int c = 0; c < 4; ++c)
            if (!isFinite(Vec3(world[c])) || !std::isfinite(world[c].w)) fail(where + " has a non-finite transform");

        if (node.mesh >= 0) addMesh(node.mesh, world, where);
        if (node.camera >= 0) addCamera(node.camera, world, where);
        auto ext = node.extensions.find("KHR_lights_punctual");
        if (ext != node.extensions.end() && ext->second.Has("light")) {
            int li = ext->second.Get("light").GetNumberAsInt();
            if (li < 0 || li >= int(lightTemplates_.size())) fail(where + " references light " + std::to_string(li) + " which does not exist");
            PunctualLight l = lightTemplates_[li];
            l.position = Vec3(world[3]);
            l.direction = glm::normalize(-Vec3(world[2]));
            scene_.lights.push_back(l);
        }
        for (int child : node.children) visitNode(child, world, depth + 1);
    }

    void addCamera(int index, const Mat4& world, const std::string& nodeWhere) {
        if (index >= int(model_.cameras.size())) fail(nodeWhere + " references camera " + std::to_string(index) + " which does not exist");
        const tinygltf::Camera& c = model_.cameras[index];
        if (c.type != "perspective") {
            reporter_.warn(path_ + ": " + quoted("camera", index, c.name) + " is " + c.type + "; only perspective cameras are used");
            return;
        }
        Camera cam;
        cam.name = c.name.empty() ? "camera " + std::to_string(index) : c.name;
        cam.position = Vec3(world[3]);
        cam.forward = glm::normalize(-Vec3(world[2]));
        cam.right = glm::normalize(glm::cross(cam.forward, Vec3(world[1])));
        cam.up = glm::cross(cam.right, cam.forward);
        cam.yfov = float(c.perspective.yfov);
        cam.aspect = float(c.perspective.aspectRatio);
        if (!(cam.yfov > 0.f && cam.yfov < kPi) || !isFinite(cam.forward) || !isFinite(cam.right))
            fail(quoted("camera", index, c.name) + " has an invalid yfov or transform");
        scene_.cameras.push_back(cam);
    }

    // -- Accessors -----------------------------------------------------------------------
    // Reads accessor `index` as `n` floats per element (normalized integers become [0,1]),
    // checking every byte it touches lies inside its buffer.
    std::vector<float> readFloats(int index, int n, const std::string& where) {
        const tinygltf::Accessor& a = accessor(index, where);
        if (tinygltf::GetNumComponentsInType(a.type) != n)
            fail(where + ": " + quoted("accessor", index, a.name) + " has the wrong type");
        std::vector<float> out(a.count * n, 0.f);
        forEachComponent(index, where, [&](size_t e, int c, const unsigned char* p) {
            float v = 0.f;
            switch (a.componentType) {
                case TINYGLTF_COMPONENT_TYPE_FLOAT: std::memcpy(&v, p, 4); break;
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: v = *p / 255.f; break;
                case TINYGLTF_COMPONENT_TYPE_BYTE: v = std::max(float(int8_t(*p)) / 127.f, -1.f); break;
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t u; std::memcpy(&u, p, 2); v = u / 65535.f; break; }
                case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t u; std::memcpy(&u, p, 2); v = std::max(u / 32767.f, -1.f); break; }
                default: fail(where + ": " + quoted("accessor", index, a.name) + " has an unsupported component type");
            }
            out[e * n + c] = v;
        });
        return out;
    }

    std::vector<uint32_t> readIndices(int index, const std::string& where) {
        const tinygltf::Accessor& a = accessor(index, where);
        if (a.type != TINYGLTF_TYPE_SCALAR) fail(where + ": index " + quoted("accessor", index, a.name) + " is not scalar");
        std::vector<uint32_t> out(a.count);
        forEachComponent(index, where, [&](size_t e, int, const unsigned char* p) {
            switch (a.componentType) {
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: out[e] = *p; break;
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t u; std::memcpy(&u, p, 2); out[e] = u; break; }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: std::memcpy(&out[e], p, 4); break;
                default: fail(where + ": index " + quoted("accessor", index, a.name) + " has a non-integer component type");
            }
        });
        return out;
    }

    const tinygltf::Accessor& accessor(int index, const std::string& where) {
        if (index < 0 || index >= int(model_.accessors.size()))
            fail(where + ": accessor " + std::to_string(index) + " does not exist");
        const tinygltf::Accessor& a = model_.accessors[index];
        if (a.sparse.isSparse) fail(where + ": " + quoted("accessor", index, a.name) + " is sparse, which is not supported");
        return a;
    }

    template <class F>
    void forEachComponent(int index, const std::string& where, F&& f) {
        const tinygltf::Accessor& a = model_.accessors[index];
        std::string awhere = where + ": " + quoted("accessor", index, a.name);
        int n = tinygltf::GetNumComponentsInType(a.type);
        int size = tinygltf::GetComponentSizeInBytes(a.componentType);
        if (n <= 0 || size <= 0) fail(awhere + " has an invalid type");
        if (a.bufferView < 0) {  // all zeros per the spec
            static const unsigned char zeros[8] = {};
            for (size_t e = 0; e < a.count; ++e)
                for (int c = 0; c < n; ++c) f(e, c, zeros);
            return;
        }
        if (a.bufferView >= int(model_.bufferViews.size())) fail(awhere + " references a missing bufferView");
        const tinygltf::BufferView& view = model_.bufferViews[a.bufferView];
        if (view.buffer < 0 || view.buffer >= int(model_.buffers.size())) fail(awhere + " references a missing buffer");
        const std::vector<unsigned char>& data = model_.buffers[view.buffer].data;
        size_t stride = view.byteStride ? view.byteStride : size_t(n) * size;
        size_t begin = view.byteOffset + a.byteOffset;
        size_t needed = a.count == 0 ? 0 : a.byteOffset + stride * (a.count - 1) + size_t(n) * size;
        if (needed > view.byteLength || view.byteOffset + view.byteLength > data.size())
            fail(awhere + " reads past the end of its bufferView or buffer");
        for (size_t e = 0; e < a.count; ++e)
            for (int c = 0; c < n; ++c) f(e, c, &data[begin + e * stride + size_t(c) * size]);
    }

    // -- Meshes --------------------------------------------------------------------------
    void addMesh(int meshIndex, const Mat4& world, const std::string& nodeWhere) {
        if (meshIndex >= int(model_.meshes.size())) fail(nodeWhere + " references mesh " + std::to_string(meshIndex) + " which does not exist");
        const tinygltf::Mesh& mesh = model_.meshes[meshIndex];
        glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(world)));
        bool flip = glm::determinant(glm::mat3(world)) < 0.f;

        for (size_t pi = 0; pi < mesh.primitives.size(); ++pi) {
            const tinygltf::Primitive& prim = mesh.primitives[pi];
            std::string where = quoted("mesh", meshIndex, mesh.name) + " primitive " + std::to_string(pi) + " (" + nodeWhere + ")";
            int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
            if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN) {
                reporter_.warn(path_ + ": " + where + " is not made of triangles (mode " + std::to_string(mode) + "): skipped");
                continue;
            }
            auto pos = prim.attributes.find("POSITION");
            if (pos == prim.attributes.end()) fail(where + " has no POSITION attribute");
            std::vector<float> p = readFloats(pos->second, 3, where);
            size_t nv = p.size() / 3;
            std::vector<float> nrm, uv;
            if (auto it = prim.attributes.find("NORMAL"); it != prim.attributes.end()) {
                nrm = readFloats(it->second, 3, where);
                if (nrm.size() != p.size()) fail(where + ": NORMAL and POSITION counts differ");
            }
            int texCoord = 0;
            uint32_t material = defaultMaterial_;
            if (prim.material >= 0) {
                if (prim.material >= int(model_.materials.size())) fail(where + " references material " + std::to_string(prim.material) + " which does not exist");
                material = uint32_t(prim.material);
                texCoord = model_.materials[prim.material].pbrMetallicRoughness.baseColorTexture.texCoord;
            }
            if (auto it = prim.attributes.find("TEXCOORD_" + std::to_string(texCoord)); it != prim.attributes.end()) {
                uv = readFloats(it->second, 2, where);
                if (uv.size() / 2 != nv) fail(where + ": TEXCOORD and POSITION counts differ");
            }

            std::vector<uint32_t> idx;
            if (prim.indices >= 0) {
                idx = readIndices(prim.indices, where);
                for (uint32_t i : idx)
                    if (i >= nv) fail(where + ": index " + std::to_string(i) + " is out of range (" + std::to_string(nv) + " vertices)");
            } else {
                idx.resize(nv);
                for (size_t i = 0; i < nv; ++i) idx[i] = uint32_t(i);
            }
            std::vector<uint32_t> tris = triangulate(idx, mode);

            // Vertices to world space; NaNs and infinities are errors, not holes.
            std::vector<Vec3> wp(nv), wn(nrm.empty() ? 0 : nv);
            for (size_t v = 0; v < nv; ++v) {
                Vec3 q(p[3 * v], p[3 * v + 1], p[3 * v + 2]);
                if (!isFinite(q)) fail(where + ": vertex " + std::to_string(v) + " is not finite");
                wp[v] = Vec3(world * Vec4(q, 1.f));
                if (!nrm.empty()) wn[v] = normalMatrix * Vec3(nrm[3 * v], nrm[3 * v + 1], nrm[3 * v + 2]);
            }

            uint32_t object = uint32_t(scene_.objectNames.size());
            scene_.objectNames.push_back(where);
            for (size_t t = 0; t + 2 < tris.size(); t += 3) {
                uint32_t i0 = tris[t], i1 = tris[t + 1], i2 = tris[t + 2];
                if (flip) std::swap(i1, i2);
                Vec3 e = glm::cross(wp[i1] - wp[i0], wp[i2] - wp[i0]);
                if (!(glm::dot(e, e) > 0.f)) continue;  // degenerate: no area, nothing to hit
                Vec3 ng = glm::normalize(e);
                for (uint32_t i : {i0, i1, i2}) {
                    scene_.positions.push_back(wp[i]);
                    Vec3 n = ng;
                    if (!wn.empty()) {
                        float len = glm::length(wn[i]);
                        if (std::isfinite(len) && len > 1e-12f) n = wn[i] / len;
                    }
                    scene_.normals.push_back(n);
                    scene_.uvs.push_back(uv.empty() ? Vec2(0.f) : Vec2(uv[2 * i], uv[2 * i + 1]));
                }
                scene_.triMaterial.push_back(material);
                scene_.triObject.push_back(object);
            }
        }
    }

    static std::vector<uint32_t> triangulate(const std::vector<uint32_t>& idx, int mode) {
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            std::vector<uint32_t> t(idx.begin(), idx.begin() + idx.size() / 3 * 3);
            return t;
        }
        std::vector<uint32_t> t;
        for (size_t i = 2; i < idx.size(); ++i) {
            if (mode == TINYGLTF_MODE_TRIANGLE_FAN) t.insert(t.end(), {idx[0], idx[i - 1], idx[i]});
            else if (i % 2 == 0) t.insert(t.end(), {idx[i - 2], idx[i - 1], idx[i]});
            else t.insert(t.end(), {idx[i - 1], idx[i - 2], idx[i]});
        }
        return t;
    }

    std::string path_;
    Reporter& reporter_;
    tinygltf::Model model_;
    Scene scene_;
    uint32_t defaultMaterial_ = 0;
    std::vector<PunctualLight> lightTemplates_;
    std::map<int, int> textureOfImage_;
    std::string gltfWarning_;  // tinygltf's first warning line, reported after a successful load
};

}  // namespace

Scene loadScene(const std::string& path, Reporter& reporter) { return Loader(path, reporter).load(); }

// -- Scene queries ---------------------------------------------------------------------------

Vec3 Texture::sample(Vec2 uv) const {
    float x = (uv.x - std::floor(uv.x)) * width - 0.5f;
    float y = (uv.y - std::floor(uv.y)) * height - 0.5f;
    int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    float fx = x - x0, fy = y - y0;
    auto at = [&](int i, int j) {
        i = ((i % width) + width) % width;
        j = ((j % height) + height) % height;
        return texels[size_t(j) * width + i];
    };
    return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
           fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

Vec3 PunctualLight::intensityTowards(const Vec3& w) const {
    if (type != LightType::Spot) return intensity;
    float c = glm::dot(w, direction);
    if (c <= cosOuter) return Vec3(0.f);
    if (c >= cosInner) return intensity;
    float t = (c - cosOuter) / (cosInner - cosOuter);
    return intensity * (t * t);
}

Vec3 Scene::geometricNormal(size_t tri) const {
    const Vec3* p = &positions[3 * tri];
    return glm::normalize(glm::cross(p[1] - p[0], p[2] - p[0]));
}

float Scene::triangleArea(size_t tri) const {
    const Vec3* p = &positions[3 * tri];
    return 0.5f * glm::length(glm::cross(p[1] - p[0], p[2] - p[0]));
}

Vec3 Scene::albedo(uint32_t material, Vec2 uv) const {
    const Material& m = materials[material];
    if (m.baseColorTexture < 0) return m.baseColor;
    return m.baseColor * textures[m.baseColorTexture].sample(uv);
}

Camera Scene::camera(const std::string& name) const {
    if (!name.empty()) {
        for (const Camera& c : cameras)
            if (c.name == name) return c;
        throw Error(ErrorKind::Config, path + ": no camera named '" + name + "'");
    }
    if (!cameras.empty()) return cameras.front();
    // Frame the bounds: look along -Z from in front of the box, the whole box in view.
    Camera c;
    c.name = "framing";
    c.yfov = 0.7f;
    Vec3 centre = bounds.center();
    float radius = 0.5f * std::max(bounds.diagonal(), 1e-3f);
    float dist = radius / std::sin(0.5f * c.yfov);
    c.position = centre + Vec3(0.f, 0.f, dist);
    return c;
}

Vec3 Scene::emittedPower() const {
    Vec3 total(0.f);
    for (size_t t = 0; t < triangleCount(); ++t)
        total += materials[triMaterial[t]].emission * kPi * triangleArea(t);
    float r = 0.5f * bounds.diagonal();
    for (const PunctualLight& l : lights) {
        switch (l.type) {
            case LightType::Point: total += 4.f * kPi * l.intensity; break;
            case LightType::Spot:
                // ∫ over the cone with the smooth falloff: full inside, quadratic ramp outside.
                total += 2.f * kPi * l.intensity * ((1.f - l.cosInner) + (l.cosInner - l.cosOuter) / 3.f);
                break;
            case LightType::Directional: total += l.intensity * kPi * r * r; break;
        }
    }
    return total;
}

void Scene::computeBounds() {
    bounds = Bounds3();
    for (const Vec3& p : positions) bounds.extend(p);
}

}  // namespace rs
