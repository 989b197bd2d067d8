// The Scene's queries (textures, punctual lights, triangles, cameras, emitted power) and
// loadScene, which hands the file to the glTF loader (gltf_loader.h).
#include "scene/scene.h"

#include <cmath>

#include "core/error.h"
#include "scene/gltf_loader.h"

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

Scene loadScene(const std::string& path, Reporter& reporter, int threads, const std::vector<Mat4>* pose) {
    return gltf::GltfLoader(path, reporter, threads, pose).load();
}

SceneFile::SceneFile(const std::string& path, Reporter& reporter, int threads)
    : loader_(std::make_unique<gltf::GltfLoader>(path, reporter, threads)) {
    // load()'s steps, its scene kept in the loader for the poses to come.
    Scene rest = loader_->load();
    loader_->scene() = std::move(rest);
    loader_->quiet();
}

SceneFile::~SceneFile() = default;

const Scene& SceneFile::scene() const { return loader_->scene(); }

const Scene& SceneFile::pose(const std::vector<Mat4>& pose) {
    loader_->flatten(&pose);
    return loader_->scene();
}

// -- Scene queries ---------------------------------------------------------------------------

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

float Scene::uvPerWorld(size_t tri, int set) const {
    const std::vector<Vec2>& in = set == 1 ? uvs1 : uvs;
    if (in.size() < 3 * tri + 3) return 0.f;
    const Vec2* uv = &in[3 * tri];
    const Vec2 a = uv[1] - uv[0], b = uv[2] - uv[0];
    const float uvArea = 0.5f * std::abs(a.x * b.y - a.y * b.x), area = triangleArea(tri);
    return area > 0.f ? std::sqrt(uvArea / area) : 0.f;
}

bool Scene::hasCutouts() const {
    for (const Material& m : materials)
        if (m.alphaMode != AlphaMode::Opaque) return true;
    return false;
}

bool Scene::solidAt(uint32_t tri, float b1, float b2, float u) const {
    const Material& m = materials[triMaterial[tri]];
    if (m.alphaMode == AlphaMode::Opaque) return true;
    const float a = alphaAt(triMaterial[tri], attributesAt(tri, b1, b2));
    return m.alphaMode == AlphaMode::Mask ? a >= m.alphaCutoff : u < a;
}

int Scene::cameraIndex(const std::string& which) const {
    if (which.empty()) return cameras.empty() ? -1 : 0;
    // Exporters often leave cameras unnamed (Blender names the node, not the camera): the
    // camera's name first, then its node's, then its index.
    for (size_t i = 0; i < cameras.size(); ++i)
        if (cameras[i].name == which) return int(i);
    for (size_t i = 0; i < cameras.size(); ++i)
        if (cameras[i].node == which) return int(i);
    if (which.find_first_not_of("0123456789") == std::string::npos && which.size() < 10) {
        const size_t index = std::stoul(which);
        if (index < cameras.size()) return int(index);
    }
    std::string known;
    for (size_t i = 0; i < cameras.size(); ++i)
        known += (i ? ", " : "") + std::to_string(i) + " '" + cameras[i].name + "'" +
                 (cameras[i].node.empty() ? "" : " on node '" + cameras[i].node + "'");
    throw Error(ErrorKind::Config, path + ": no camera '" + which + "' by name, node name or index (" +
                                       (known.empty() ? "the file has none" : "cameras: " + known) + ")");
}

Camera Scene::camera(const std::string& which) const {
    const int index = cameraIndex(which);
    if (index >= 0) return cameras[size_t(index)];
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
        if (materials[triMaterial[t]].isEmissive()) total += meanEmission(t) * kPi * triangleArea(t);
    for (const PunctualLight& l : lights) total += l.power(l.intensity, 0.5f * bounds.diagonal());
    return total;
}

void Scene::computeBounds() {
    bounds = Bounds3();
    for (const Vec3& p : positions) bounds.extend(p);
    for (const Vec3& p : portals) bounds.extend(p);
}

}  // namespace rs
