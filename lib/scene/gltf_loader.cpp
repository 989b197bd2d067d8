// The glTF loader's entry, the file, the node hierarchy and cameras (gltf_loader.h).
#include "scene/gltf_loader.h"

#include <filesystem>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <map>
#include <set>

namespace rs::gltf {

namespace {

const std::set<std::string> kSupportedExtensions = {
    "KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_transmission",
    "KHR_materials_ior", "KHR_texture_transform", "KHR_mesh_quantization"};

// Material extensions read past without being honoured: what each would add.
const std::map<std::string, std::string> kIgnoredMaterialExtensions = {
    {"KHR_materials_anisotropy", "anisotropic highlights"},
    {"KHR_materials_clearcoat", "a clear coat layer"},
    {"KHR_materials_diffuse_transmission", "diffuse transmission"},
    {"KHR_materials_dispersion", "dispersion"},
    {"KHR_materials_iridescence", "thin-film iridescence"},
    {"KHR_materials_pbrSpecularGlossiness", "the specular-glossiness model"},
    {"KHR_materials_sheen", "a sheen layer"},
    {"KHR_materials_specular", "the specular strength and colour"},
    {"KHR_materials_unlit", "unlit shading"},
    {"KHR_materials_volume", "volume attenuation and thickness"}};

std::string firstLine(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    size_t nl = s.find('\n');
    return nl == std::string::npos ? s : s.substr(0, nl);
}

}  // namespace

Scene GltfLoader::load() {
    try {
        return loadAll();
    } catch (...) {
        reportRepeatedWarnings();  // before the error that follows them
        throw;
    }
}

void GltfLoader::warn(const std::string& kind, const std::string& message) {
    if (repeated_[kind]++ == 0) reporter_->warn(path_ + ": " + message);
}

void GltfLoader::reportRepeatedWarnings() {
    for (const auto& [kind, count] : repeated_)
        if (count > 1) reporter_->warn(path_ + ": … and " + std::to_string(count - 1) + " more " + kind);
    repeated_.clear();
}

Scene GltfLoader::loadAll() {
    read();
    flatten(pose_);
    // These warnings only once the load succeeded: a failed load is one error line.
    warnIgnoredFeatures();
    if (!gltfWarning_.empty()) reporter_->warn(path_ + ": " + gltfWarning_);
    return std::move(scene_);
}

void GltfLoader::read() {
    readFile();
    checkExtensions();
    scene_.path = path_;
    loadMaterials();
    decodeImages();
    loadLights();
    loadAnimations();
}

void GltfLoader::flatten(const std::vector<Mat4>* pose) {
    if (pose && pose->size() != model_.nodes.size()) fail("the pose does not match the file's nodes", ErrorKind::Internal);
    pose_ = pose;
    // What the nodes place: a scene flattened before at another pose loses it.
    Scene& s = scene_;
    for (auto* v : {&s.positions, &s.normals, &s.portals}) v->clear();
    for (auto* v : {&s.uvs, &s.uvs1}) v->clear();
    for (auto* v : {&s.colors, &s.tangents}) v->clear();
    for (auto* v : {&s.triMaterial, &s.triObject}) v->clear();
    s.animation.cameraNode.clear();
    s.objectNames.clear();
    s.lights.clear();
    s.cameras.clear();

    // Flatten the node hierarchy of the default scene into world space.
    if (model_.scenes.empty()) fail("the file has no scene");
    int sceneIndex = model_.defaultScene >= 0 ? model_.defaultScene : 0;
    if (sceneIndex >= int(model_.scenes.size())) fail("'scene' " + std::to_string(sceneIndex) + " does not exist");
    for (int root : model_.scenes[sceneIndex].nodes) visitNode(root, Mat4(1.f), 0);
    readEnvironment(model_.scenes[sceneIndex].extras, quoted("scene", sceneIndex, model_.scenes[sceneIndex].name));
    computeMissingTangents(scene_);

    if (scene_.triangleCount() == 0) fail("the scene has no triangles");
    scene_.computeBounds();
    reportRepeatedWarnings();
}

void GltfLoader::readEnvironment(const tinygltf::Value& extras, const std::string& where) {
    if (!extras.IsObject()) return;
    auto number = [&](const char* key, float& out) {
        if (!extras.Has(key)) return;
        const tinygltf::Value& v = extras.Get(key);
        if (!v.IsNumber() || !std::isfinite(v.GetNumberAsDouble())) fail(where + ": extras." + key + " is not a number");
        out = float(v.GetNumberAsDouble());
    };
    if (extras.Has("raysplat_sky")) {
        const tinygltf::Value& v = extras.Get("raysplat_sky");
        if (!v.IsArray() || v.ArrayLen() != 3) fail(where + ": extras.raysplat_sky is not three numbers");
        for (int c = 0; c < 3; ++c) {
            const tinygltf::Value& x = v.Get(c);
            if (!x.IsNumber() || !(x.GetNumberAsDouble() >= 0.0)) fail(where + ": extras.raysplat_sky has a negative or non-number value");
            scene_.environment.sky[c] = float(x.GetNumberAsDouble());
        }
    }
    if (extras.Has("raysplat_env")) {
        const tinygltf::Value& v = extras.Get("raysplat_env");
        if (!v.IsString() || v.Get<std::string>().empty()) fail(where + ": extras.raysplat_env is not a file name");
        // Relative to the glTF file.
        scene_.environment.file = (std::filesystem::path(path_).parent_path() / v.Get<std::string>()).string();
    }
    number("raysplat_env_strength", scene_.environment.strength);
    number("raysplat_env_rotation", scene_.environment.rotation);
}

void GltfLoader::fail(const std::string& what, ErrorKind kind) const {
    throw Error(kind, path_ + ": " + what);
}

void GltfLoader::readFile() {
    std::error_code ec;
    if (!std::filesystem::exists(path_, ec)) fail("no such file", ErrorKind::Io);
    if (std::filesystem::is_directory(path_, ec)) fail("is a directory, not a glTF file", ErrorKind::Io);
    tinygltf::TinyGLTF gltf;
    gltf.SetImageLoader(&GltfLoader::keepEncodedImage, nullptr);
    std::string err, warn;
    std::string ext = std::filesystem::path(path_).extension().string();
    for (char& c : ext) c = char(std::tolower(c));
    bool ok = ext == ".glb" ? gltf.LoadBinaryFromFile(&model_, &err, &warn, path_)
                            : gltf.LoadASCIIFromFile(&model_, &err, &warn, path_);
    if (!ok) fail("cannot load glTF: " + firstLine(err.empty() ? "unknown error" : err));
    if (!warn.empty()) gltfWarning_ = firstLine(warn);
}

void GltfLoader::checkExtensions() {
    for (const std::string& e : model_.extensionsRequired)
        if (!kSupportedExtensions.count(e))
            fail("required extension '" + e + "' is not supported");
    for (const std::string& e : model_.extensionsUsed) quantized_ = quantized_ || e == "KHR_mesh_quantization";
}

void GltfLoader::warnIgnoredFeatures() {
    // Feature → the first object that uses it and how many do: one line a feature.
    std::map<std::string, std::pair<std::string, int>> uses;
    auto use = [&](const std::string& feature, const std::string& object) {
        if (uses[feature].second++ == 0) uses[feature].first = object;
    };
    for (size_t i = 0; i < model_.materials.size(); ++i)
        for (const auto& [name, value] : model_.materials[i].extensions)
            if (auto it = kIgnoredMaterialExtensions.find(name); it != kIgnoredMaterialExtensions.end())
                use(name + " (" + it->second + ")", quoted("material", int(i), model_.materials[i].name));
    for (size_t i = 0; i < model_.meshes.size(); ++i)
        for (const tinygltf::Primitive& prim : model_.meshes[i].primitives)
            if (!prim.targets.empty()) {
                use("morph targets (the base shape is rendered)", quoted("mesh", int(i), model_.meshes[i].name));
                break;
            }
    for (size_t i = 0; i < model_.nodes.size(); ++i)
        if (model_.nodes[i].skin >= 0)
            use("skins (the mesh is rendered unposed, where its node puts it)", quoted("node", int(i), model_.nodes[i].name));
    for (const std::string& e : model_.extensionsUsed)
        if (!kSupportedExtensions.count(e) && !kIgnoredMaterialExtensions.count(e)) use("extension " + e, "the file's extensionsUsed");
    for (const auto& [feature, u] : uses)
        reporter_->warn(path_ + ": ignored: " + feature + " in " + u.first +
                       (u.second > 1 ? " and " + std::to_string(u.second - 1) + " more" : ""));
}

bool GltfLoader::isPortal(const tinygltf::Node& node) {
    if (!node.extras.IsObject() || !node.extras.Has(kPortalProperty)) return false;
    const tinygltf::Value& v = node.extras.Get(kPortalProperty);
    return v.IsBool() ? v.Get<bool>() : v.IsNumber() ? v.GetNumberAsDouble() != 0.0 : false;
}

void GltfLoader::visitNode(int index, const Mat4& parent, int depth) {
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
    if (pose_) local = (*pose_)[index];
    Mat4 world = parent * local;
    for (int c = 0; c < 4; ++c)
        if (!isFinite(Vec3(world[c])) || !std::isfinite(world[c].w)) fail(where + " has a non-finite transform");

    if (node.mesh >= 0) {
        if (isPortal(node)) {
            // A light portal (docs/design.md §7): its triangles leave the scene for scene_.portals.
            const size_t triangles = scene_.triangleCount(), objects = scene_.objectNames.size();
            addMesh(node.mesh, world, where);
            scene_.portals.insert(scene_.portals.end(), scene_.positions.begin() + 3 * triangles, scene_.positions.end());
            scene_.keepTriangles(triangles);
            scene_.objectNames.resize(objects);
        } else {
            addMesh(node.mesh, world, where);
        }
    }
    if (node.camera >= 0) {
        const size_t cameras = scene_.cameras.size();
        addCamera(node.camera, world, where, node.name);
        if (scene_.cameras.size() > cameras) scene_.animation.cameraNode.push_back(index);
    }
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

void GltfLoader::addCamera(int index, const Mat4& world, const std::string& nodeWhere, const std::string& nodeName) {
    if (index >= int(model_.cameras.size())) fail(nodeWhere + " references camera " + std::to_string(index) + " which does not exist");
    const tinygltf::Camera& c = model_.cameras[index];
    const std::string where = quoted("camera", index, c.name);
    Camera cam;
    cam.name = c.name.empty() ? "camera " + std::to_string(index) : c.name;
    cam.node = nodeName;
    // The node's axes without its scale: the camera looks down its -Z, +Y up.
    cam.position = Vec3(world[3]);
    cam.forward = glm::normalize(-Vec3(world[2]));
    cam.right = glm::normalize(glm::cross(cam.forward, Vec3(world[1])));
    cam.up = glm::cross(cam.right, cam.forward);
    if (!isFinite(cam.forward) || !isFinite(cam.right)) fail(where + " (" + nodeWhere + ") has a degenerate transform");
    if (c.type == "perspective") {
        cam.yfov = float(c.perspective.yfov);
        cam.aspect = float(c.perspective.aspectRatio);
        if (!(cam.yfov > 0.f && cam.yfov < kPi)) fail(where + " has an invalid yfov");
    } else if (c.type == "orthographic") {
        // xmag and ymag are half the view's width and height (glTF 2.0 §3.10.3).
        const double xmag = c.orthographic.xmag, ymag = c.orthographic.ymag;
        if (!(xmag > 0.0 && ymag > 0.0 && std::isfinite(xmag / ymag) && std::isfinite(ymag)))
            fail(where + " has an invalid xmag or ymag (not positive numbers)");
        cam.projection = Projection::Orthographic;
        cam.ymag = float(ymag);
        cam.aspect = float(xmag / ymag);
    } else {
        warn("cameras of an unknown type (not used)", where + " is '" + c.type + "', neither perspective nor orthographic: not used");
        return;
    }
    scene_.cameras.push_back(cam);
}

}  // namespace rs::gltf
