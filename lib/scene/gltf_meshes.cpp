// The glTF loader's accessors (every byte they touch checked against its buffer) and meshes:
// triangles in world space (gltf_loader.h).
#include "scene/gltf_loader.h"

#include <cstring>
#include <functional>

namespace rs::gltf {

// Reads accessor `index` as `n` floats per element (normalized integers become [0,1]),
// checking every byte it touches lies inside its buffer.
std::vector<float> GltfLoader::readFloats(int index, int n, const std::string& where) {
    const tinygltf::Accessor& a = accessor(index, where);
    if (tinygltf::GetNumComponentsInType(a.type) != n)
        fail(where + ": " + quoted("accessor", index, a.name) + " has the wrong type");
    std::vector<float> out(a.count * n, 0.f);
    forEachComponent(index, where, [&](size_t e, int c, const unsigned char* p) {
        float v = 0.f;
        switch (a.componentType) {
            case TINYGLTF_COMPONENT_TYPE_FLOAT: std::memcpy(&v, p, 4); break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: v = *p / 255.f; break;
            case TINYGLTF_COMPONENT_TYPE_BYTE: v = std::max(float(int8_t(*p)) / 127.f, -1.f); break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t u; std::memcpy(&u, p, 2); v = u / 65535.f; break; }
            case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t u; std::memcpy(&u, p, 2); v = std::max(u / 32767.f, -1.f); break; }
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
        std::vector<float> p = readFloats(pos->second, 3, where);
        size_t nv = p.size() / 3;
        std::vector<float> nrm, uv;
        if (auto it = prim.attributes.find("NORMAL"); it != prim.attributes.end()) {
            nrm = readFloats(it->second, 3, where);
            if (nrm.size() != p.size()) fail(where + ": NORMAL and POSITION counts differ");
        }
        int texCoord = 0;
        uint32_t material = defaultMaterial_;
        if (prim.material >= 0) {
            if (prim.material >= int(model_.materials.size())) fail(where + " references material " + std::to_string(prim.material) + " which does not exist");
            material = uint32_t(prim.material);
            texCoord = model_.materials[prim.material].pbrMetallicRoughness.baseColorTexture.texCoord;
        }
        if (auto it = prim.attributes.find("TEXCOORD_" + std::to_string(texCoord)); it != prim.attributes.end()) {
            uv = readFloats(it->second, 2, where);
            if (uv.size() / 2 != nv) fail(where + ": TEXCOORD and POSITION counts differ");
        }

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
                scene_.uvs.push_back(uv.empty() ? Vec2(0.f) : Vec2(uv[2 * i], uv[2 * i + 1]));
            }
            scene_.triMaterial.push_back(material);
            scene_.triObject.push_back(object);
        }
    }
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
