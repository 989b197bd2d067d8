// The glTF loader's materials (the table of docs/design.md §3): every texture slot of the
// metallic-roughness model with KHR_texture_transform (occlusionTexture is left out on purpose:
// global illumination computes what it approximates), textures and KHR_lights_punctual
// lights (gltf_loader.h).
#include "scene/gltf_loader.h"

#include <cmath>

namespace rs::gltf {

namespace {

double extNumber(const tinygltf::ExtensionMap& ext, const char* extension, const char* key,
                 double fallback) {
    auto it = ext.find(extension);
    if (it == ext.end() || !it->second.Has(key)) return fallback;
    const tinygltf::Value& v = it->second.Get(key);
    return v.IsNumber() ? v.GetNumberAsDouble() : fallback;
}

}  // namespace

void GltfLoader::loadMaterials() {
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
        out.baseColorTexture = textureRef(pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord,
                                          pbr.baseColorTexture.extensions, where, true);
        out.metallicRoughnessTexture = textureRef(pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord,
                                                  pbr.metallicRoughnessTexture.extensions, where, false);
        out.normalTexture = textureRef(m.normalTexture.index, m.normalTexture.texCoord, m.normalTexture.extensions, where, false);
        out.normalScale = float(m.normalTexture.scale);
        out.emissiveTexture = textureRef(m.emissiveTexture.index, m.emissiveTexture.texCoord, m.emissiveTexture.extensions,
                                         where, true);
        if (!std::isfinite(out.normalScale)) fail(where + " has a non-finite normalTexture scale");
        needsTangents_ = needsTangents_ || out.normalTexture.present();
        out.opacity = std::clamp(float(pbr.baseColorFactor.at(3)), 0.f, 1.f);
        out.alphaCutoff = float(m.alphaCutoff);
        if (m.alphaMode == "MASK") out.alphaMode = AlphaMode::Mask;
        else if (m.alphaMode == "BLEND") out.alphaMode = AlphaMode::Blend;
        else if (m.alphaMode != "OPAQUE" && !m.alphaMode.empty()) fail(where + " has unknown alphaMode '" + m.alphaMode + "'");
        if (!std::isfinite(out.opacity) || !std::isfinite(out.alphaCutoff) || out.alphaCutoff < 0.f)
            fail(where + " has a non-finite alpha or a negative alphaCutoff");

        if (transmission > 0.f) {
            if (transmission < 1.f)
                reporter_->warn(path_ + ": " + where + ": transmission " + std::to_string(transmission) +
                               " treated as " + (transmission >= 0.5f ? "1" : "0"));
        }
        if (transmission >= 0.5f) out.kind = MaterialKind::Glass;
        else if (out.metallicRoughnessTexture.present()) out.kind = MaterialKind::Mix;  // varies over the surface
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

TextureRef GltfLoader::textureRef(int index, int texCoord, const tinygltf::ExtensionMap& extensions,
                                  const std::string& where, bool srgb) {
    TextureRef ref;
    if (index < 0) return ref;
    ref.texture = loadTexture(index, where, srgb);
    ref.texCoord = texCoord;
    if (auto it = extensions.find("KHR_texture_transform"); it != extensions.end()) {
        const tinygltf::Value& v = it->second;
        const std::string twhere = where + ": texture " + std::to_string(index) + "'s KHR_texture_transform";
        auto pair = [&](const char* key, Vec2& out) {
            if (!v.Has(key)) return;
            const tinygltf::Value& a = v.Get(key);
            if (!a.IsArray() || a.ArrayLen() != 2 || !a.Get(0).IsNumber() || !a.Get(1).IsNumber())
                fail(twhere + " has a " + key + " that is not two numbers");
            out = Vec2(float(a.Get(0).GetNumberAsDouble()), float(a.Get(1).GetNumberAsDouble()));
        };
        pair("offset", ref.transform.offset);
        pair("scale", ref.transform.scale);
        if (v.Has("rotation")) {
            if (!v.Get("rotation").IsNumber()) fail(twhere + " has a rotation that is not a number");
            ref.transform.rotation = float(v.Get("rotation").GetNumberAsDouble());
        }
        if (v.Has("texCoord")) {
            if (!v.Get("texCoord").IsInt()) fail(twhere + " has a texCoord that is not an integer");
            ref.texCoord = v.Get("texCoord").GetNumberAsInt();
        }
        if (!isFinite(Vec3(ref.transform.offset, ref.transform.rotation)) || !isFinite(Vec3(ref.transform.scale, 0.f)))
            fail(twhere + " has a non-finite offset, rotation or scale");
    }
    if (ref.texCoord < 0) fail(where + ": texture " + std::to_string(index) + " has a negative texCoord");
    if (ref.texCoord > 1) {
        warn("texture slots reading TEXCOORD_2 or above (TEXCOORD_0 read)",
             where + ": texture " + std::to_string(index) + " reads TEXCOORD_" + std::to_string(ref.texCoord) +
                 "; only TEXCOORD_0 and TEXCOORD_1 are read (TEXCOORD_0 used)");
        ref.texCoord = 0;
    }
    usesTexCoord1_ = usesTexCoord1_ || ref.texCoord == 1;
    return ref;
}

int GltfLoader::loadTexture(int textureIndex, const std::string& where, bool srgb) {
    if (textureIndex < 0 || textureIndex >= int(model_.textures.size()))
        fail(where + ": texture " + std::to_string(textureIndex) + " does not exist");
    int source = model_.textures[textureIndex].source;
    if (source < 0 || source >= int(model_.images.size()))
        fail(quoted("texture", textureIndex, model_.textures[textureIndex].name) + " has no valid image source");
    auto cached = textureOfImage_.find({source, srgb});
    if (cached != textureOfImage_.end()) return cached->second;
    const tinygltf::Image& img = model_.images[source];
    const int index = int(scene_.textures.size());
    scene_.textures.emplace_back();
    scene_.textures.back().name = quoted("image", source, img.name.empty() ? img.uri : img.name);
    textureOfImage_[{source, srgb}] = index;
    return index;
}

void GltfLoader::loadLights() {
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

}  // namespace rs::gltf
