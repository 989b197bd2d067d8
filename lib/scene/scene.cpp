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

Scene loadScene(const std::string& path, Reporter& reporter) { return gltf::GltfLoader(path, reporter).load(); }

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

int Texture::texelAt(Vec2 uv) const {
    const float fx = uv.x - std::floor(uv.x), fy = uv.y - std::floor(uv.y);
    const int x = std::min(int(fx * float(width)), width - 1), y = std::min(int(fy * float(height)), height - 1);
    return y * width + x;
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

float Scene::alphaAt(uint32_t material, Vec2 uv) const {
    const Material& m = materials[material];
    if (m.baseColorTexture < 0) return m.opacity;
    const Texture& t = textures[m.baseColorTexture];
    return t.alpha.empty() ? m.opacity : m.opacity * t.alpha[size_t(t.texelAt(uv))];
}

bool Scene::hasCutouts() const {
    for (const Material& m : materials)
        if (m.alphaMode != AlphaMode::Opaque) return true;
    return false;
}

bool Scene::solidAt(uint32_t tri, float b1, float b2, float u) const {
    const Material& m = materials[triMaterial[tri]];
    if (m.alphaMode == AlphaMode::Opaque) return true;
    const Vec2 uv = (1.f - b1 - b2) * uvs[3 * tri] + b1 * uvs[3 * tri + 1] + b2 * uvs[3 * tri + 2];
    const float a = alphaAt(triMaterial[tri], uv);
    return m.alphaMode == AlphaMode::Mask ? a >= m.alphaCutoff : u < a;
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
    for (const PunctualLight& l : lights) total += l.power(l.intensity, 0.5f * bounds.diagonal());
    return total;
}

void Scene::computeBounds() {
    bounds = Bounds3();
    for (const Vec3& p : positions) bounds.extend(p);
    for (const Vec3& p : portals) bounds.extend(p);
}

}  // namespace rs
