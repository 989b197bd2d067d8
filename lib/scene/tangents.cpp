// Tangents for normal maps whose mesh gives none (scene.h's computeMissingTangents), with
// MikkTSpace's conventions, the ones Blender's glTF exporter writes and glTF viewers assume:
// the tangent follows +u; the bitangent follows the image's +Y, which is −v in glTF's uvs (v
// grows downwards), and w says on which side of cross(normal, tangent) it lies. Corners that
// share their mesh, position, normal and uv share one tangent: the angle-weighted mean of their
// triangles' directions, each first projected onto the corner's tangent plane.
#include <cstring>
#include <string>
#include <unordered_map>

#include "scene/scene.h"

namespace rs {

namespace {

// A triangle's +u and image-+Y directions (unnormalized); false when its uvs have no area.
bool triangleFrame(const Vec3 p[3], const Vec2 uv[3], Vec3& dpdu, Vec3& up) {
    const Vec3 e1 = p[1] - p[0], e2 = p[2] - p[0];
    const Vec2 d1 = uv[1] - uv[0], d2 = uv[2] - uv[0];
    const float det = d1.x * d2.y - d2.x * d1.y;
    if (!(std::abs(det) > 1e-20f)) return false;
    dpdu = (e1 * d2.y - e2 * d1.y) / det;
    up = -(e2 * d1.x - e1 * d2.x) / det;  // −∂p/∂v
    return std::isfinite(glm::dot(dpdu, dpdu)) && std::isfinite(glm::dot(up, up));
}

Vec3 onPlane(const Vec3& v, const Vec3& n) {
    const Vec3 w = v - n * glm::dot(n, v);
    const float l = glm::length(w);
    return l > 1e-20f ? w / l : Vec3(0.f);
}

}  // namespace

void computeMissingTangents(Scene& s) {
    if (s.tangents.empty()) return;
    struct Sum {
        Vec3 t{0.f}, b{0.f};
    };
    std::unordered_map<std::string, uint32_t> groupOf;
    std::vector<Sum> sums;
    std::vector<uint32_t> cornerGroup(s.tangents.size(), UINT32_MAX);
    for (size_t tri = 0; tri < s.triangleCount(); ++tri) {
        const Material& m = s.materials[s.triMaterial[tri]];
        if (!m.normalTexture.present()) continue;
        const size_t c0 = 3 * tri;
        if (s.tangents[c0].w != 0.f && s.tangents[c0 + 1].w != 0.f && s.tangents[c0 + 2].w != 0.f) continue;
        const std::vector<Vec2>& uvs = m.normalTexture.texCoord == 1 && !s.uvs1.empty() ? s.uvs1 : s.uvs;
        Vec3 dpdu, up;
        if (!triangleFrame(&s.positions[c0], &uvs[c0], dpdu, up)) continue;
        for (int k = 0; k < 3; ++k) {
            const size_t c = c0 + size_t(k);
            if (s.tangents[c].w != 0.f) continue;
            // The corner's key: its mesh, position, normal and uv, bit for bit.
            std::string key(sizeof(uint32_t) + 8 * sizeof(float), '\0');
            char* at = key.data();
            std::memcpy(at, &s.triObject[tri], 4);
            std::memcpy(at + 4, &s.positions[c], 12);
            std::memcpy(at + 16, &s.normals[c], 12);
            std::memcpy(at + 28, &uvs[c], 8);
            auto [it, added] = groupOf.try_emplace(std::move(key), uint32_t(sums.size()));
            if (added) sums.emplace_back();
            cornerGroup[c] = it->second;
            const Vec3 a = s.positions[c0 + (k + 1) % 3] - s.positions[c], b = s.positions[c0 + (k + 2) % 3] - s.positions[c];
            const float angle = std::acos(std::clamp(glm::dot(glm::normalize(a), glm::normalize(b)), -1.f, 1.f));
            const Vec3& n = s.normals[c];
            sums[it->second].t += angle * onPlane(dpdu, n);
            sums[it->second].b += angle * onPlane(up, n);
        }
    }
    for (size_t c = 0; c < s.tangents.size(); ++c) {
        if (s.tangents[c].w != 0.f) continue;
        const Vec3& n = s.normals[c];
        Vec3 t = cornerGroup[c] == UINT32_MAX ? Vec3(0.f) : onPlane(sums[cornerGroup[c]].t, n);
        // No uv direction to follow (degenerate uvs, or no normal map here): any tangent.
        if (glm::dot(t, t) == 0.f) t = Frame(n).s;
        const Vec3 b = cornerGroup[c] == UINT32_MAX ? Vec3(0.f) : sums[cornerGroup[c]].b;
        s.tangents[c] = Vec4(t, glm::dot(glm::cross(n, t), b) < 0.f ? -1.f : 1.f);
    }
}

}  // namespace rs
