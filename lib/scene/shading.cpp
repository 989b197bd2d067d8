// The Scene's materials at a surface point (scene.h): the interpolated vertex attributes, the
// texture slots read through their uv set and KHR_texture_transform, COLOR_0, metallic and
// roughness, textured emission and the tangent-space normal map. Textures hold linear values
// (the colour ones decoded from sRGB when they were loaded).
#include <cmath>

#include "core/sampling.h"
#include "scene/scene.h"

namespace rs {

Vec2 TextureTransform::apply(Vec2 uv) const {
    const Vec2 s = scale * uv;
    if (rotation == 0.f) return offset + s;
    const float c = std::cos(rotation), n = std::sin(rotation);
    return offset + Vec2(c * s.x + n * s.y, -n * s.x + c * s.y);
}

ShadingAttributes Scene::attributesAt(uint32_t tri, float b1, float b2) const {
    const size_t i = 3 * size_t(tri);
    const float b0 = 1.f - b1 - b2;
    ShadingAttributes a;
    a.uv[0] = b0 * uvs[i] + b1 * uvs[i + 1] + b2 * uvs[i + 2];
    if (!uvs1.empty()) a.uv[1] = b0 * uvs1[i] + b1 * uvs1[i + 1] + b2 * uvs1[i + 2];
    if (!colors.empty()) a.color = b0 * colors[i] + b1 * colors[i + 1] + b2 * colors[i + 2];
    return a;
}

Vec2 Scene::cornerTextureUv(const TextureRef& ref, size_t tri, int k) const {
    const size_t i = 3 * tri + size_t(k);
    const Vec2 uv = ref.texCoord == 1 ? (uvs1.empty() ? Vec2(0.f) : uvs1[i]) : uvs[i];
    return ref.transform.apply(uv);
}

float Scene::uvFootprint(const TextureRef& ref, float footprint, size_t tri) const {
    if (!(footprint > 0.f)) return 0.f;
    const Vec2 s = ref.transform.scale;
    return footprint * uvPerWorld(tri, ref.texCoord) * std::sqrt(std::abs(s.x * s.y));
}

Vec3 Scene::albedo(uint32_t material, const ShadingAttributes& a, float footprint, uint32_t tri) const {
    const Material& m = materials[material];
    Vec3 c = m.baseColor * Vec3(a.color);
    if (!m.baseColorTexture.present()) return c;
    const Texture& t = textures[size_t(m.baseColorTexture.texture)];
    return c * Vec3(t.sample(textureUv(m.baseColorTexture, a), t.lodOf(uvFootprint(m.baseColorTexture, footprint, tri))));
}

float Scene::alphaAt(uint32_t material, const ShadingAttributes& a) const {
    const Material& m = materials[material];
    float alpha = m.opacity * a.color.w;
    if (!m.baseColorTexture.present()) return alpha;
    // The texel holding the point, not a filtered value: see Texture::texelAt.
    const Texture& t = textures[size_t(m.baseColorTexture.texture)];
    return t.hasAlpha() ? alpha * t.alphaAt(t.texelAt(textureUv(m.baseColorTexture, a))) : alpha;
}

Vec2 Scene::metallicRoughness(uint32_t material, const ShadingAttributes& a) const {
    const Material& m = materials[material];
    Vec2 mr(m.metallic, m.roughness);
    if (!m.metallicRoughnessTexture.present()) return mr;
    const Vec4 t = textures[size_t(m.metallicRoughnessTexture.texture)].sample(textureUv(m.metallicRoughnessTexture, a));
    return glm::clamp(mr * Vec2(t.z, t.y), Vec2(0.f), Vec2(1.f));
}

Vec3 Scene::emissionAt(uint32_t material, const ShadingAttributes& a) const {
    const Material& m = materials[material];
    if (!m.emissiveTexture.present()) return m.emission;
    return m.emission * Vec3(textures[size_t(m.emissiveTexture.texture)].sample(textureUv(m.emissiveTexture, a)));
}

Vec3 Scene::meanEmission(size_t tri) const {
    const uint32_t material = triMaterial[tri];
    if (!materials[material].emissiveTexture.present()) return materials[material].emission;
    // The texture over the triangle by 256 points of a (0,2)-sequence: the emitter's power
    // chooses it among the lights and is reported; what it emits is read texel by texel.
    constexpr uint32_t kPoints = 256;
    DVec3 sum(0.0);
    for (uint32_t i = 0; i < kPoints; ++i) {
        const Vec2 b = sampleUniformTriangle(sobol2D(i, 0));
        sum += DVec3(emissionAt(material, attributesAt(uint32_t(tri), b.x, b.y)));
    }
    return Vec3(sum / double(kPoints));
}

Vec3 Scene::shadingNormalAt(uint32_t tri, float b1, float b2, const ShadingAttributes& a) const {
    const size_t i = 3 * size_t(tri);
    const float b0 = 1.f - b1 - b2;
    Vec3 n = b0 * normals[i] + b1 * normals[i + 1] + b2 * normals[i + 2];
    const float len = glm::length(n);
    n = len > 1e-8f ? n / len : geometricNormal(tri);
    const Material& m = materials[triMaterial[tri]];
    if (!m.normalTexture.present() || tangents.empty()) return n;
    // The tangent frame at the point: the interpolated tangent made orthogonal to the normal,
    // the bitangent cross(n, t)·w (glTF's TANGENT).
    const Vec4 t4 = b0 * tangents[i] + b1 * tangents[i + 1] + b2 * tangents[i + 2];
    Vec3 t = Vec3(t4) - n * glm::dot(n, Vec3(t4));
    const float tl = glm::length(t);
    if (!(tl > 1e-8f)) return n;
    t /= tl;
    const Vec3 b = glm::cross(n, t) * (t4.w < 0.f ? -1.f : 1.f);
    const Vec4 texel = textures[size_t(m.normalTexture.texture)].sample(textureUv(m.normalTexture, a));
    const Vec3 c = 2.f * Vec3(texel) - Vec3(1.f);
    const Vec3 mapped = (c.x * m.normalScale) * t + (c.y * m.normalScale) * b + c.z * n;
    const float ml = glm::length(mapped);
    return ml > 1e-8f && std::isfinite(ml) ? mapped / ml : n;
}

void Scene::keepTriangles(size_t n) {
    positions.resize(3 * n);
    normals.resize(3 * n);
    uvs.resize(3 * n);
    if (!uvs1.empty()) uvs1.resize(3 * n);
    if (!colors.empty()) colors.resize(3 * n);
    if (!tangents.empty()) tangents.resize(3 * n);
    triMaterial.resize(n);
    triObject.resize(n);
}

}  // namespace rs
