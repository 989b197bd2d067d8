// The glTF loader's accessors (every byte they touch checked against its buffer) and meshes:
// triangles in world space (gltf_loader.h).
#include "scene/gltf_loader.h"

#include <cstring>
#include <functional>

namespace rs::gltf {

// Reads accessor `index` as `n` floats per element (gltf_loader.h), checking every byte it
// touches lies inside its buffer.
std::vector<float> GltfLoader::readFloats(int index, int n, const std::string& where, bool values) {
    const tinygltf::Accessor& a = accessor(index, where);
    if (tinygltf::GetNumComponentsInType(a.type) != n)
        fail(where + ": " + quoted("accessor", index, a.name) + " has the wrong type");
    std::vector<float> out(a.count * n, 0.f);
    // An integer's divisor: its largest value where it is normalized, 1 where it is its value.
    const bool raw = values && !a.normalized;
    forEachComponent(index, where, [&](size_t e, int c, const unsigned char* p) {
        float v = 0.f;
        switch (a.componentType) {
            case TINYGLTF_COMPONENT_TYPE_FLOAT: std::memcpy(&v, p, 4); break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: v = raw ? float(*p) : *p / 255.f; break;
            case TINYGLTF_COMPONENT_TYPE_BYTE: v = raw ? float(int8_t(*p)) : std::max(float(int8_t(*p)) / 127.f, -1.f); break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t u; std::memcpy(&u, p, 2); v = raw ? float(u) : u / 65535.f; break; }
            case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t u; std::memcpy(&u, p, 2); v = raw ? float(u) : std::max(u / 32767.f, -1.f); break; }
            default: fail(where + ": " + quoted("accessor", index, a.name) + " has an unsupported component type");
        }
        out[e * n + c] = v;
    });
    return out;
}

std::vector<uint32_t> GltfLoader::readIndices(int index, const std::string& where) {
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

const tinygltf::Accessor& GltfLoader::accessor(int index, const std::string& where) {
    if (index < 0 || index >= int(model_.accessors.size()))
        fail(where + ": accessor " + std::to_string(index) + " does not exist");
    return model_.accessors[index];
}

// The bytes [offset, offset + length) of bufferView `view`, checked against the view and its
// buffer.
const unsigned char* GltfLoader::viewBytes(int view, size_t offset, size_t length, const std::string& what) {
    if (view < 0 || view >= int(model_.bufferViews.size())) fail(what + " references a missing bufferView");
    const tinygltf::BufferView& v = model_.bufferViews[view];
    if (v.buffer < 0 || v.buffer >= int(model_.buffers.size())) fail(what + " references a missing buffer");
    const std::vector<unsigned char>& data = model_.buffers[v.buffer].data;
    if (offset > v.byteLength || length > v.byteLength - offset || v.byteOffset > data.size() ||
        v.byteLength > data.size() - v.byteOffset)
        fail(what + " reads past the end of its bufferView or buffer");
    return data.data() + v.byteOffset + offset;
}

template <class F>
void GltfLoader::forEachComponent(int index, const std::string& where, F&& f) {
    const tinygltf::Accessor& a = model_.accessors[index];
    std::string awhere = where + ": " + quoted("accessor", index, a.name);
    int n = tinygltf::GetNumComponentsInType(a.type);
    int size = tinygltf::GetComponentSizeInBytes(a.componentType);
    if (n <= 0 || size <= 0) fail(awhere + " has an invalid type");
    if (a.bufferView < 0) {  // all zeros per the spec
        static const unsigned char zeros[8] = {};
        for (size_t e = 0; e < a.count; ++e)
            for (int c = 0; c < n; ++c) f(e, c, zeros);
        forEachSparseComponent(index, where, f);
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
    forEachSparseComponent(index, where, f);
}

// A sparse accessor (glTF 2.0 §3.6.2.3): after the dense elements (or zeros without a
// bufferView), element sparse.indices[k] becomes sparse.values[k], each index checked against
// the accessor's count and every byte against its bufferView.
template <class F>
void GltfLoader::forEachSparseComponent(int index, const std::string& where, F&& f) {
    const tinygltf::Accessor& a = model_.accessors[index];
    if (!a.sparse.isSparse) return;
    const std::string awhere = where + ": sparse " + quoted("accessor", index, a.name);
    const int n = tinygltf::GetNumComponentsInType(a.type), size = tinygltf::GetComponentSizeInBytes(a.componentType);
    const auto& sp = a.sparse;
    if (sp.count < 1 || size_t(sp.count) > a.count)
        fail(awhere + " substitutes " + std::to_string(sp.count) + " of its " + std::to_string(a.count) + " elements");
    const int indexType = sp.indices.componentType;
    if (indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        fail(awhere + " has sparse indices that are not unsigned integers");
    if (sp.indices.byteOffset < 0 || sp.values.byteOffset < 0) fail(awhere + " has a negative byteOffset");
    const size_t count = size_t(sp.count), indexSize = size_t(tinygltf::GetComponentSizeInBytes(indexType));
    const unsigned char* indices = viewBytes(sp.indices.bufferView, size_t(sp.indices.byteOffset), count * indexSize,
                                             awhere + "'s indices");
    const unsigned char* values = viewBytes(sp.values.bufferView, size_t(sp.values.byteOffset), count * size_t(n) * size,
                                            awhere + "'s values");
    for (size_t k = 0; k < count; ++k) {
        uint32_t e = 0;
        if (indexSize == 1) e = indices[k];
        else if (indexSize == 2) { uint16_t u; std::memcpy(&u, indices + 2 * k, 2); e = u; }
        else std::memcpy(&e, indices + 4 * k, 4);
        if (e >= a.count)
            fail(awhere + ": index " + std::to_string(e) + " is past its " + std::to_string(a.count) + " elements");
        for (int c = 0; c < n; ++c) f(size_t(e), c, values + (k * size_t(n) + size_t(c)) * size_t(size));
    }
}

void GltfLoader::addMesh(int meshIndex, const Mat4& world, const std::string& nodeWhere) {
    if (meshIndex >= int(model_.meshes.size())) fail(nodeWhere + " references mesh " + std::to_string(meshIndex) + " which does not exist");
    const tinygltf::Mesh& mesh = model_.meshes[meshIndex];
    glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(world)));
    bool flip = glm::determinant(glm::mat3(world)) < 0.f;

    for (size_t pi = 0; pi < mesh.primitives.size(); ++pi) {
        const tinygltf::Primitive& prim = mesh.primitives[pi];
        std::string where = quoted("mesh", meshIndex, mesh.name) + " primitive " + std::to_string(pi) + " (" + nodeWhere + ")";
        int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN) {
            warn("primitives that are not triangles (skipped)",
                 where + " is not made of triangles (mode " + std::to_string(mode) + "): skipped");
            continue;
        }
        auto pos = prim.attributes.find("POSITION");
        if (pos == prim.attributes.end()) fail(where + " has no POSITION attribute");
        std::vector<float> p = readFloats(pos->second, 3, where, quantized_);
        size_t nv = p.size() / 3;
        std::vector<float> nrm;
        if (auto it = prim.attributes.find("NORMAL"); it != prim.attributes.end()) {
            nrm = readFloats(it->second, 3, where);
            if (nrm.size() != p.size()) fail(where + ": NORMAL and POSITION counts differ");
        }
        uint32_t material = defaultMaterial_;
        if (prim.material >= 0) {
            if (prim.material >= int(model_.materials.size())) fail(where + " references material " + std::to_string(prim.material) + " which does not exist");
            material = uint32_t(prim.material);
        }
        VertexExtras extra = readVertexExtras(prim, material, nv, where);

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
        extra.toWorld(glm::mat3(world), flip);

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
                extra.push(scene_, i);
            }
            scene_.triMaterial.push_back(material);
            scene_.triObject.push_back(object);
        }
    }
}

GltfLoader::VertexExtras GltfLoader::readVertexExtras(const tinygltf::Primitive& prim, uint32_t material, size_t nv,
                                                     const std::string& where) {
    VertexExtras x;
    auto attribute = [&](const char* name) {
        auto it = prim.attributes.find(name);
        return it == prim.attributes.end() ? -1 : it->second;
    };
    auto read = [&](const char* name, int n, std::vector<float>& out, bool values = false) {
        const int a = attribute(name);
        if (a < 0) return;
        out = readFloats(a, n, where, values);
        if (out.size() != nv * size_t(n)) fail(where + ": " + name + " and POSITION counts differ");
    };
    read("TEXCOORD_0", 2, x.uv0, quantized_);
    x.keepUv1 = usesTexCoord1_;
    if (x.keepUv1) read("TEXCOORD_1", 2, x.uv1, quantized_);
    if (const int a = attribute("COLOR_0"); a >= 0) {
        const tinygltf::Accessor& acc = accessor(a, where);
        const int n = tinygltf::GetNumComponentsInType(acc.type);
        if ((n != 3 && n != 4) || (acc.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT &&
                                   acc.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                                   acc.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT))
            fail(where + ": COLOR_0 " + quoted("accessor", a, acc.name) + " is not VEC3 or VEC4 of floats, bytes or shorts");
        std::vector<float> c;
        read("COLOR_0", n, c);
        x.color.assign(4 * nv, 1.f);
        for (size_t v = 0; v < nv; ++v)
            for (int k = 0; k < n; ++k) x.color[4 * v + size_t(k)] = c[size_t(n) * v + size_t(k)];
        for (float f : x.color)
            if (!(f >= 0.f && f <= 1e30f)) fail(where + ": COLOR_0 has a negative or non-finite value");
        // COLOR_0 is kept from the first primitive that has it on; the earlier ones are white.
        if (scene_.colors.empty()) scene_.colors.assign(scene_.positions.size(), Vec4(1.f));
    }
    x.keepColors = !scene_.colors.empty() || !x.color.empty();
    x.keepTangents = needsTangents_;
    if (const int a = attribute("TANGENT"); a >= 0) {
        const tinygltf::Accessor& acc = accessor(a, where);
        // KHR_mesh_quantization also allows normalized bytes and shorts.
        const bool integer = acc.normalized && (acc.componentType == TINYGLTF_COMPONENT_TYPE_BYTE ||
                                                acc.componentType == TINYGLTF_COMPONENT_TYPE_SHORT);
        if (acc.type != TINYGLTF_TYPE_VEC4 || (acc.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT && !(quantized_ && integer)))
            fail(where + ": TANGENT " + quoted("accessor", a, acc.name) + " is not VEC4 of floats" +
                 (quantized_ ? " or of normalized bytes or shorts" : ""));
        if (x.keepTangents && material < model_.materials.size() && model_.materials[material].normalTexture.index >= 0)
            read("TANGENT", 4, x.tangent);
    }
    return x;
}

// Tangents turn with the node (they lie in the surface, unlike normals); a mirroring node
// turns the bitangent's side. A tangent that is zero or not finite is left to be computed.
void GltfLoader::VertexExtras::toWorld(const glm::mat3& m, bool flip) {
    for (size_t v = 0; 4 * v < tangent.size(); ++v) {
        float* t = &tangent[4 * v];
        const Vec3 w = m * Vec3(t[0], t[1], t[2]);
        const float len = glm::length(w);
        const bool ok = std::isfinite(len) && len > 1e-12f && std::isfinite(t[3]);
        const Vec3 unit = ok ? w / len : Vec3(0.f);
        t[0] = unit.x, t[1] = unit.y, t[2] = unit.z;
        t[3] = !ok ? 0.f : (t[3] < 0.f) != flip ? -1.f : 1.f;
    }
}

void GltfLoader::VertexExtras::push(Scene& s, uint32_t i) const {
    s.uvs.push_back(uv0.empty() ? Vec2(0.f) : Vec2(uv0[2 * i], uv0[2 * i + 1]));
    if (keepUv1) s.uvs1.push_back(uv1.empty() ? Vec2(0.f) : Vec2(uv1[2 * i], uv1[2 * i + 1]));
    if (keepColors) s.colors.push_back(color.empty() ? Vec4(1.f) : Vec4(color[4 * i], color[4 * i + 1], color[4 * i + 2], color[4 * i + 3]));
    if (keepTangents) s.tangents.push_back(tangent.empty() ? Vec4(0.f) : Vec4(tangent[4 * i], tangent[4 * i + 1], tangent[4 * i + 2], tangent[4 * i + 3]));
}

std::vector<uint32_t> GltfLoader::triangulate(const std::vector<uint32_t>& idx, int mode) {
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

}  // namespace rs::gltf
