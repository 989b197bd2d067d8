// The glTF loader (docs/design.md §3): one class whose parts live in four files —
// gltf_loader.cpp (the file, the node hierarchy, cameras), gltf_materials.cpp (materials,
// textures, KHR_lights_punctual), gltf_images.cpp (decoding the images, in parallel, once the
// materials said which textures they need) and gltf_meshes.cpp (accessors, meshes). Internal to
// lib/scene/: only these files include tinygltf (Debian's compiled library: no
// TINYGLTF_IMPLEMENTATION here). Every error names the file and the glTF object it was found
// in; nothing is dropped silently: non-triangle primitives are skipped with a warning.
#pragma once

#include <tiny_gltf.h>

#include <map>
#include <utility>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/log.h"
#include "scene/scene.h"

namespace rs::gltf {

// "material 3 'red'": how messages name a glTF object.
inline std::string quoted(const std::string& kind, int index, const std::string& name) {
    std::string s = kind + " " + std::to_string(index);
    if (!name.empty()) s += " '" + name + "'";
    return s;
}

class GltfLoader {
public:
    // threads: for decoding images (0: one per hardware thread). With `pose`
    // (SceneAnimation::pose: every node's local transform), the nodes are flattened as posed
    // instead of as the file writes them.
    GltfLoader(const std::string& path, Reporter& reporter, int threads = 0, const std::vector<Mat4>* pose = nullptr)
        : path_(path), reporter_(&reporter), threads_(threads), pose_(pose) {}
    Scene load();

    // The two halves of load(), for a file flattened at many poses (SceneFile): read() parses the
    // file, its materials, textures (decoded), lights and animations, once; flatten() places what
    // the nodes carry — triangles, portals, punctual lights, cameras — at `pose` (nullptr: the
    // file's transforms) into scene(), replacing what an earlier flatten placed.
    void read();
    void flatten(const std::vector<Mat4>* pose);
    Scene& scene() { return scene_; }
    // Warnings from here on go nowhere: a walkthrough's later poses say nothing the first did not.
    void quiet() { reporter_ = &silentReporter(); }

private:
    Scene loadAll();
    // A warning of a kind is printed the first time; the rest of that kind are counted and
    // summed up as "… and N more <kind>" when the load ends (one line, not one per object).
    void warn(const std::string& kind, const std::string& message);
    void reportRepeatedWarnings();

    // -- The file, the node hierarchy, cameras (gltf_loader.cpp)
    [[noreturn]] void fail(const std::string& what, ErrorKind kind = ErrorKind::Scene) const;
    void readFile();
    void checkExtensions();
    // One warning a glTF feature or extension the file uses and the renderer ignores (material
    // extensions, morph targets, skins, unknown extensions), naming the first object that uses it.
    void warnIgnoredFeatures();
    void visitNode(int index, const Mat4& parent, int depth);
    void addCamera(int index, const Mat4& world, const std::string& nodeWhere, const std::string& nodeName);
    // The scene's extras raysplat_sky [r, g, b], raysplat_env (a file beside the glTF),
    // raysplat_env_strength and raysplat_env_rotation: Scene::environment.
    void readEnvironment(const tinygltf::Value& extras, const std::string& where);
    // A node whose extras (Blender: the object's custom properties, exported with "Include:
    // Custom Properties") set raysplat_portal to true or 1 is a light portal, not geometry.
    static constexpr const char* kPortalProperty = "raysplat_portal";
    static bool isPortal(const tinygltf::Node& node);
    // -- Animations and the node hierarchy (gltf_animation.cpp)
    void loadNodeHierarchy();
    void loadAnimations();
    AnimationChannel loadChannel(const tinygltf::Animation& a, const tinygltf::AnimationChannel& ch, const std::string& where);
    // -- Materials, textures, KHR_lights_punctual (gltf_materials.cpp)
    void loadMaterials();
    // A texture slot: the texture (loaded once per image and colour space), its uv set and its
    // KHR_texture_transform.
    TextureRef textureRef(int index, int texCoord, const tinygltf::ExtensionMap& extensions, const std::string& where,
                          bool srgb);
    // The Scene::textures index of glTF texture `textureIndex`, one per (image, srgb): colour
    // textures (base colour, emission) are sRGB, data textures (normals, metallic-roughness)
    // linear. Only reserves the slot: decodeImages fills it.
    int loadTexture(int textureIndex, const std::string& where, bool srgb = true);
    void loadLights();
    // -- Images (gltf_images.cpp)
    // tinygltf's image callback: keeps a file's encoded bytes (or nothing, for an image in a
    // bufferView) instead of decoding them while the JSON is parsed, one image after another.
    static bool keepEncodedImage(tinygltf::Image* image, int index, std::string* err, std::string* warn,
                                 int width, int height, const unsigned char* bytes, int size, void* user);
    // Decodes every image a texture uses, in parallel, into Scene::textures, freeing each
    // encoded copy once its textures are built.
    void decodeImages();
    void decodeImage(int image, int srgbTexture, int linearTexture);
    // An image's encoded bytes, from the file or its bufferView (checked against its buffer).
    std::pair<const unsigned char*, size_t> encodedBytes(const tinygltf::Image& image, const std::string& where) const;
    // Its RGBA size once decoded, from the header; 0 where the header cannot be read.
    size_t decodedBytes(int image) const;
    // -- Accessors and meshes (gltf_meshes.cpp)
    // Reads accessor `index` as `n` floats per element (integers normalized, to [0,1] or [−1,1]),
    // checking every byte it touches lies inside its buffer. With `values`, the integers of an
    // accessor not marked `normalized` are their values (KHR_mesh_quantization's positions and
    // texture coordinates).
    std::vector<float> readFloats(int index, int n, const std::string& where, bool values = false);
    std::vector<uint32_t> readIndices(int index, const std::string& where);
    const tinygltf::Accessor& accessor(int index, const std::string& where);
    template <class F>
    void forEachComponent(int index, const std::string& where, F&& f);
    template <class F>
    void forEachSparseComponent(int index, const std::string& where, F&& f);
    const unsigned char* viewBytes(int view, size_t offset, size_t length, const std::string& what);
    void addMesh(int meshIndex, const Mat4& world, const std::string& nodeWhere);
    // A primitive's optional vertex attributes, as the Scene keeps them: TEXCOORD_0, TEXCOORD_1
    // (when a texture slot reads it), COLOR_0 (RGB given alpha 1) and TANGENT (when its
    // material has a normal map); empty where the primitive has none.
    struct VertexExtras {
        std::vector<float> uv0, uv1, color, tangent;  // 2, 2, 4, 4 floats a vertex
        bool keepUv1 = false, keepColors = false, keepTangents = false;
        void toWorld(const glm::mat3& m, bool flip);
        void push(Scene& s, uint32_t vertex) const;
    };
    VertexExtras readVertexExtras(const tinygltf::Primitive& prim, uint32_t material, size_t nv, const std::string& where);
    static std::vector<uint32_t> triangulate(const std::vector<uint32_t>& idx, int mode);

    std::string path_;
    Reporter* reporter_;
    int threads_ = 0;
    const std::vector<Mat4>* pose_;
    tinygltf::Model model_;
    Scene scene_;
    uint32_t defaultMaterial_ = 0;
    std::vector<PunctualLight> lightTemplates_;
    std::map<std::pair<int, bool>, int> textureOfImage_;  // (image, srgb) → Scene::textures index
    bool usesTexCoord1_ = false;  // some texture slot reads TEXCOORD_1
    bool needsTangents_ = false;  // some material has a normal map
    bool quantized_ = false;      // the file uses KHR_mesh_quantization
    std::map<std::string, int> repeated_;  // warnings by kind
    std::string gltfWarning_;  // tinygltf's first warning line, reported after a successful load
};

}  // namespace rs::gltf
