// Scene: the glTF file flattened into world-space triangles, materials, lights and a camera
// (docs/design.md §3). World space is glTF's: metres, right-handed, +Y up. Colours are linear RGB,
// emission is radiance in W/(m²·sr), punctual intensities in W/sr, directional in W/m².
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/math.h"
#include "scene/animation.h"
#include "scene/texture.h"

namespace rs {

enum class MaterialKind { Lambert, Glossy, Mix, Glass, Mirror };
const char* materialKindName(MaterialKind kind);

// glTF's alphaMode: OPAQUE ignores alpha; MASK cuts the surface away where alpha < alphaCutoff;
// BLEND keeps it with probability alpha (stochastic transparency: each ray decides by a hash
// of itself, so a render stays deterministic).
enum class AlphaMode { Opaque, Mask, Blend };

struct Material {
    std::string name;
    MaterialKind kind = MaterialKind::Lambert;
    Vec3 baseColor{0.8f};
    float metallic = 0.f;
    float roughness = 1.f;
    float ior = 1.5f;
    int baseColorTexture = -1;  // index into Scene::textures, or -1
    Vec3 emission{0.f};         // radiance of the front face, W/(m²·sr)
    AlphaMode alphaMode = AlphaMode::Opaque;
    float opacity = 1.f;        // baseColorFactor's alpha
    float alphaCutoff = 0.5f;   // MASK

    bool isEmissive() const { return !isBlack(emission); }
    bool isSpecular() const { return kind == MaterialKind::Glass || kind == MaterialKind::Mirror; }
    float alpha() const { return std::max(roughness * roughness, 1e-3f); }  // GGX α
};

enum class LightType { Point, Spot, Directional };

struct PunctualLight {
    std::string name;
    LightType type = LightType::Point;
    Vec3 position{0.f};
    Vec3 direction{0, 0, -1};  // where it shines (spot, directional), unit
    Vec3 intensity{1.f};       // colour × intensity: W/sr (point, spot) or W/m² (directional)
    float cosInner = 1.f, cosOuter = 0.f;  // spot cone

    // Intensity towards direction `w` (unit, away from the light); glTF's smooth cone falloff.
    Vec3 intensityTowards(const Vec3& w) const;
    // The power it emits, for an intensity I given as a colour or as its luminance: 4πI (point);
    // over the cone with the smooth falloff, full inside and a quadratic ramp outside (spot);
    // through a disc of the scene's bounding radius (directional).
    template <class T>
    T power(const T& I, float sceneRadius) const {
        switch (type) {
            case LightType::Point: return 4.f * kPi * I;
            case LightType::Spot: return 2.f * kPi * I * ((1.f - cosInner) + (cosInner - cosOuter) / 3.f);
            case LightType::Directional: return kPi * sqr(sceneRadius) * I;
        }
        return T(0.f);
    }
};

// Perspective: rays from `position` through the image plane, `yfov` the vertical field.
// Orthographic: parallel rays along `forward` from the plane through `position`, a view
// 2·ymag metres high. Either way the image's width follows from its height and the image's
// aspect (as glTF's aspectRatio, or xmag / ymag, gives it by default).
enum class Projection { Perspective, Orthographic };

struct Camera {
    std::string name = "default";
    std::string node;        // the name of the node that places it; empty when unnamed or none
    Projection projection = Projection::Perspective;
    Vec3 position{0.f};
    Vec3 right{1, 0, 0}, up{0, 1, 0}, forward{0, 0, -1};  // unit, world space
    float yfov = 0.7f;       // radians (perspective)
    float ymag = 1.f;        // half the view's height, metres (orthographic)
    float aspect = 0.f;      // width / height from the file, 0 when not given
};

struct Scene {
    std::string path;  // the file it came from, for messages

    // Triangle soup in world space: triangle t has vertices 3t, 3t+1, 3t+2.
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;  // shading normals, unit (geometric normal where the file had none)
    std::vector<Vec2> uvs;      // (0,0) where the file had none
    std::vector<uint32_t> triMaterial;
    std::vector<uint32_t> triObject;  // index into objectNames: "mesh 'name' (node 'name')"
    std::vector<std::string> objectNames;

    std::vector<Material> materials;
    std::vector<Texture> textures;
    std::vector<PunctualLight> lights;
    // Light portals (docs/design.md §7): the openings through which the sun and the sky light the
    // interior, 3 positions a triangle. Not geometry: nothing hits them. Photons from
    // directional lights and the environment are sent through them when there are any.
    std::vector<Vec3> portals;
    // The environment the file asks for (its scene's extras; docs/design.md §4): render options
    // (`env`, `sky`) replace it.
    struct EnvironmentSettings {
        std::string file;  // an equirectangular OpenEXR; empty: none
        float strength = 1.f, rotation = 0.f;  // rotation in degrees, as `env-rotation`
        Vec3 sky{0.f};     // a uniform sky; black: none
    } environment;
    std::vector<Camera> cameras;  // every camera the default scene's nodes place, in node order
    // The file's node hierarchy and animations (a still renders the nodes as the file writes
    // them; a walkthrough poses them a frame at a time).
    SceneAnimation animation;
    Bounds3 bounds;

    size_t triangleCount() const { return triMaterial.size(); }
    Vec3 geometricNormal(size_t tri) const;  // unit, from the counter-clockwise winding
    float triangleArea(size_t tri) const;
    // Base colour at a surface point: factor × texture, filtered over a footprint `uvFootprint`
    // wide in uv units (SurfacePoint::uvFootprint; 0: bilinear in the full-size image).
    Vec3 albedo(uint32_t material, Vec2 uv, float uvFootprint = 0.f) const;
    // uv units per world unit on triangle tri: the square root of its uv area over its area
    // (0 where the uvs are degenerate). A footprint w wide on the surface is w × this in uv.
    float uvPerWorld(size_t tri) const;
    // Alpha at a surface point: factor × the level-0 texel's alpha.
    float alphaAt(uint32_t material, Vec2 uv) const;
    // Whether any material cuts its surface (alphaMode MASK or BLEND).
    bool hasCutouts() const;
    // Whether triangle `tri` is there at barycentrics (b1, b2) for a ray whose own random number
    // is u in [0, 1): MASK compares alpha with the cutoff, BLEND with u.
    bool solidAt(uint32_t tri, float b1, float b2, float u) const;
    // The camera to render: the one `which` names (its name, its node's name, or its index in
    // `cameras`, tried in that order), or the first, or one framing the bounds.
    Camera camera(const std::string& which = "") const;
    // Total flux emitted by area and punctual lights, W (directional lights count over the
    // scene's bounding-sphere disc).
    Vec3 emittedPower() const;

    void computeBounds();
};

// Loads a .gltf or .glb file, decoding its images on `threads` threads (0: one per hardware
// thread); with `pose` (SceneAnimation::pose), the nodes flattened as posed. Throws
// Error(Scene/Io) naming the file and glTF object.
Scene loadScene(const std::string& path, class Reporter& reporter, int threads = 0, const std::vector<Mat4>* pose = nullptr);

}  // namespace rs
