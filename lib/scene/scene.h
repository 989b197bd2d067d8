// Scene: the glTF file flattened into world-space triangles, materials, lights and a camera
// (docs/design.md §3). World space is glTF's: metres, right-handed, +Y up. Colours are linear RGB,
// emission is radiance in W/(m²·sr), punctual intensities in W/sr, directional in W/m².
#pragma once

#include <cstdint>
#include <memory>
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

// KHR_texture_transform: uv' = offset + R(rotation)·(scale ⊙ uv), R turning the uvs
// counter-clockwise in the image (u' = u cos + v sin, v' = −u sin + v cos, as the extension's
// example of the rotated lower-left quadrant needs).
struct TextureTransform {
    Vec2 offset{0.f}, scale{1.f};
    float rotation = 0.f;  // radians

    Vec2 apply(Vec2 uv) const;
};

// One texture slot of a material: which texture, read through which uv set and transform.
struct TextureRef {
    int texture = -1;  // index into Scene::textures, or -1: none
    int texCoord = 0;  // TEXCOORD_0 or TEXCOORD_1
    TextureTransform transform;

    bool present() const { return texture >= 0; }
};

// The glTF 2.0 metallic-roughness model (docs/design.md §3). Each value is its factor times its
// texture where it has one: base colour (× COLOR_0), metallic (B) and roughness (G) of the
// metallicRoughnessTexture, the tangent-space normal map, emission (emissiveTexture).
struct Material {
    std::string name;
    MaterialKind kind = MaterialKind::Lambert;
    Vec3 baseColor{0.8f};
    float metallic = 0.f;
    float roughness = 1.f;
    float ior = 1.5f;
    TextureRef baseColorTexture;         // sRGB; its alpha is the surface's alpha
    TextureRef metallicRoughnessTexture;  // linear: B metal, G rough
    TextureRef normalTexture;             // linear, tangent space, +Y towards the image's top
    float normalScale = 1.f;              // scales the map's X and Y
    TextureRef emissiveTexture;           // sRGB, times emission
    Vec3 emission{0.f};         // radiance of the front face, W/(m²·sr): emissiveFactor × strength
    AlphaMode alphaMode = AlphaMode::Opaque;
    float opacity = 1.f;        // baseColorFactor's alpha
    float alphaCutoff = 0.5f;   // MASK

    bool isEmissive() const { return !isBlack(emission); }
    bool isSpecular() const { return kind == MaterialKind::Glass || kind == MaterialKind::Mirror; }
    float alpha() const { return std::max(roughness * roughness, 1e-3f); }  // GGX α
};

// What a material reads at a point of a triangle: its interpolated vertex attributes.
struct ShadingAttributes {
    Vec2 uv[2] = {Vec2(0.f), Vec2(0.f)};  // TEXCOORD_0, TEXCOORD_1
    Vec4 color{1.f};                       // COLOR_0 (RGBA, linear)
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
    std::vector<Vec2> uvs;      // TEXCOORD_0, (0,0) where the file had none
    // Kept only when a file uses them (else empty): TEXCOORD_1 ((0,0) where a primitive has
    // none), COLOR_0 (RGBA, (1,1,1,1) where a primitive has none) and tangents (xyz unit, w the
    // handedness ±1: bitangent = cross(normal, tangent)·w), for the triangles with a normal map.
    std::vector<Vec2> uvs1;
    std::vector<Vec4> colors;
    std::vector<Vec4> tangents;
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
    // -- Materials at a surface point (shading.cpp)
    // The vertex attributes of triangle `tri` at barycentrics (b1, b2).
    ShadingAttributes attributesAt(uint32_t tri, float b1, float b2) const;
    // The uv at which slot `ref` reads its texture: its uv set, transformed.
    static Vec2 textureUv(const TextureRef& ref, const ShadingAttributes& a) {
        return ref.transform.apply(a.uv[ref.texCoord]);
    }
    // The uv of slot `ref` at corner k of triangle `tri`: the transform is affine, so these
    // interpolate to textureUv across the triangle.
    Vec2 cornerTextureUv(const TextureRef& ref, size_t tri, int k) const;
    // Base colour at a surface point of triangle tri: factor × texture × COLOR_0, the texture
    // filtered over a footprint `footprint` wide on the surface (SurfacePoint::footprint; 0:
    // bilinear in the full-size image).
    Vec3 albedo(uint32_t material, const ShadingAttributes& a, float footprint = 0.f, uint32_t tri = 0) const;
    // A footprint `footprint` wide on triangle tri in the uv units of texture slot `ref`: × its
    // uv set's uvPerWorld × the geometric mean of its transform's scale.
    float uvFootprint(const TextureRef& ref, float footprint, size_t tri) const;
    // uv units per world unit on triangle tri in uv set `set` (TEXCOORD_0 or _1): the square root
    // of its uv area over its area (0 where the uvs are degenerate or missing).
    float uvPerWorld(size_t tri, int set = 0) const;
    // Alpha at a surface point: factor × the texel's alpha × COLOR_0's.
    float alphaAt(uint32_t material, const ShadingAttributes& a) const;
    // (metallic, roughness) at a surface point: the factors × the texture's B and G.
    Vec2 metallicRoughness(uint32_t material, const ShadingAttributes& a) const;
    // Emitted radiance of the front face at a surface point: emission × the emissive texture.
    Vec3 emissionAt(uint32_t material, const ShadingAttributes& a) const;
    // The mean emitted radiance over triangle `tri` (its texture averaged over the triangle).
    Vec3 meanEmission(size_t tri) const;
    // The shading normal of triangle `tri` at (b1, b2): the interpolated normal, turned by the
    // material's normal map where it has one. Unit; not yet checked against the geometric side.
    Vec3 shadingNormalAt(uint32_t tri, float b1, float b2, const ShadingAttributes& a) const;
    // Keeps the first n triangles (every per-corner array with them).
    void keepTriangles(size_t n);
    // Whether any material cuts its surface (alphaMode MASK or BLEND).
    bool hasCutouts() const;
    // Whether triangle `tri` is there at barycentrics (b1, b2) for a ray whose own random number
    // is u in [0, 1): MASK compares alpha with the cutoff, BLEND with u.
    bool solidAt(uint32_t tri, float b1, float b2, float u) const;
    // The camera to render: the one `which` names (its name, its node's name, or its index in
    // `cameras`, tried in that order), or the first, or one framing the bounds.
    Camera camera(const std::string& which = "") const;
    // Its index in `cameras`: -1 for the framing camera (no `which` and no camera); throws where
    // `which` names none.
    int cameraIndex(const std::string& which = "") const;
    // Total flux emitted by area and punctual lights, W (directional lights count over the
    // scene's bounding-sphere disc); textured emitters by their texture's mean.
    Vec3 emittedPower() const;

    void computeBounds();
};

// Fills the tangents of the triangles whose material has a normal map and whose tangents are
// missing (w = 0), MikkTSpace's way (tangents.cpp).
void computeMissingTangents(Scene& scene);

// Loads a .gltf or .glb file, decoding its images on `threads` threads (0: one per hardware
// thread); with `pose` (SceneAnimation::pose), the nodes flattened as posed. Throws
// Error(Scene/Io) naming the file and glTF object.
Scene loadScene(const std::string& path, class Reporter& reporter, int threads = 0, const std::vector<Mat4>* pose = nullptr);

namespace gltf {
class GltfLoader;
}

// A glTF file read once and flattened at any number of poses: a walkthrough whose meshes or
// lights move (lib/walkthrough.h) keeps the parsed file, its materials, decoded textures, lights
// and animations across its frames, and places the nodes' triangles, lights and cameras anew
// for each. scene() after pose(p) is loadScene(path, …, &p), to the bit.
class SceneFile {
public:
    // Reads the file and flattens it as the file writes it; warnings go to `reporter`, once.
    // Throws as loadScene does.
    SceneFile(const std::string& path, class Reporter& reporter, int threads = 0);
    ~SceneFile();
    const Scene& scene() const;
    // The scene flattened at `pose` (SceneAnimation::pose), replacing the one before; silent.
    const Scene& pose(const std::vector<Mat4>& pose);

private:
    std::unique_ptr<gltf::GltfLoader> loader_;
};

}  // namespace rs
