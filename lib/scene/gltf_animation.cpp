// The glTF loader's animations and node hierarchy (gltf_loader.h): SceneAnimation, every key
// checked — counts, increasing finite times, finite values, no zero quaternion, existing nodes,
// known paths, accessor types — so that evaluating it (animation.cpp) cannot fail.
#include <cmath>
#include <glm/gtc/type_ptr.hpp>

#include "scene/gltf_loader.h"

namespace rs::gltf {

void GltfLoader::loadNodeHierarchy() {
    SceneAnimation& a = scene_.animation;
    const int count = int(model_.nodes.size());
    a.parent.assign(count, -1);
    a.rest.assign(count, NodeTransform{});
    a.nodeNames.resize(count);
    a.movesGeometry.assign(count, false);
    for (int i = 0; i < count; ++i) {
        const tinygltf::Node& node = model_.nodes[i];
        a.nodeNames[i] = quoted("node", i, node.name);
        for (int child : node.children)
            if (child >= 0 && child < count && child != i) a.parent[child] = i;
        a.movesGeometry[i] = node.mesh >= 0 || node.extensions.count("KHR_lights_punctual");
        NodeTransform& t = a.rest[i];
        if (node.matrix.size() == 16) {
            t.hasMatrix = true;
            for (int k = 0; k < 16; ++k) glm::value_ptr(t.matrix)[k] = float(node.matrix[k]);
            continue;
        }
        if (node.translation.size() == 3) t.translation = Vec3(node.translation[0], node.translation[1], node.translation[2]);
        if (node.rotation.size() == 4)
            t.rotation = glm::normalize(Quat(float(node.rotation[3]), float(node.rotation[0]), float(node.rotation[1]),
                                             float(node.rotation[2])));
        if (node.scale.size() == 3) t.scale = Vec3(node.scale[0], node.scale[1], node.scale[2]);
    }
}

void GltfLoader::loadAnimations() {
    loadNodeHierarchy();
    bool morphs = false;
    for (const tinygltf::Mesh& m : model_.meshes)
        for (const tinygltf::Primitive& p : m.primitives) morphs = morphs || !p.targets.empty();
    for (int i = 0; i < int(model_.animations.size()); ++i) {
        const tinygltf::Animation& a = model_.animations[i];
        const std::string where = quoted("animation", i, a.name);
        Animation animation;
        animation.name = a.name;
        for (int c = 0; c < int(a.channels.size()); ++c) {
            const std::string channelWhere = where + ": channel " + std::to_string(c);
            const tinygltf::AnimationChannel& ch = a.channels[c];
            if (ch.target_path == "weights") {
                morphs = true;  // morph target weights: the rest pose
                continue;
            }
            animation.channels.push_back(loadChannel(a, ch, channelWhere));
            const AnimationChannel& added = animation.channels.back();
            const bool first = animation.channels.size() == 1;
            animation.start = first ? added.times.front() : std::min(animation.start, added.times.front());
            animation.end = first ? added.times.back() : std::max(animation.end, added.times.back());
        }
        scene_.animation.animations.push_back(std::move(animation));
    }
    std::string& unsupported = scene_.animation.unsupported;
    if (!model_.skins.empty()) unsupported = std::to_string(model_.skins.size()) + " skins";
    if (morphs) unsupported += std::string(unsupported.empty() ? "" : " and ") + "morph targets";
}

AnimationChannel GltfLoader::loadChannel(const tinygltf::Animation& a, const tinygltf::AnimationChannel& ch,
                                         const std::string& where) {
    AnimationChannel out;
    // The target.
    if (ch.target_node < 0 || ch.target_node >= int(model_.nodes.size()))
        fail(where + ": node " + std::to_string(ch.target_node) + " does not exist");
    out.node = ch.target_node;
    if (ch.target_path == "translation") out.path = AnimatedPath::Translation;
    else if (ch.target_path == "rotation") out.path = AnimatedPath::Rotation;
    else if (ch.target_path == "scale") out.path = AnimatedPath::Scale;
    else fail(where + ": unknown path '" + ch.target_path + "' (translation, rotation, scale, weights)");
    if (model_.nodes[out.node].matrix.size() == 16)
        fail(where + ": " + quoted("node", out.node, model_.nodes[out.node].name) + " has a matrix, which glTF does not animate");

    // The sampler.
    if (ch.sampler < 0 || ch.sampler >= int(a.samplers.size())) fail(where + ": sampler " + std::to_string(ch.sampler) + " does not exist");
    const tinygltf::AnimationSampler& s = a.samplers[ch.sampler];
    const std::string samplerWhere = where + ": sampler " + std::to_string(ch.sampler);
    if (s.interpolation == "STEP") out.interpolation = Interpolation::Step;
    else if (s.interpolation == "LINEAR" || s.interpolation.empty()) out.interpolation = Interpolation::Linear;
    else if (s.interpolation == "CUBICSPLINE") out.interpolation = Interpolation::CubicSpline;
    else fail(samplerWhere + ": unknown interpolation '" + s.interpolation + "' (STEP, LINEAR, CUBICSPLINE)");

    // Its keys: times.
    const tinygltf::Accessor& input = accessor(s.input, samplerWhere + " input");
    if (input.type != TINYGLTF_TYPE_SCALAR || input.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
        fail(samplerWhere + ": input " + quoted("accessor", s.input, input.name) + " is not float SCALAR times");
    out.times = readFloats(s.input, 1, samplerWhere + " input");
    if (out.times.empty()) fail(samplerWhere + ": no keys");
    for (size_t k = 0; k < out.times.size(); ++k) {
        if (!std::isfinite(out.times[k])) fail(samplerWhere + ": time " + std::to_string(k) + " is not finite");
        if (k > 0 && !(out.times[k] > out.times[k - 1])) fail(samplerWhere + ": times are not increasing at key " + std::to_string(k));
    }

    // And values, three a key with CUBICSPLINE (in-tangent, value, out-tangent).
    const int n = out.path == AnimatedPath::Rotation ? 4 : 3;
    const int stride = out.interpolation == Interpolation::CubicSpline ? 3 : 1;
    const tinygltf::Accessor& output = accessor(s.output, samplerWhere + " output");
    if (tinygltf::GetNumComponentsInType(output.type) != n)
        fail(samplerWhere + ": output " + quoted("accessor", s.output, output.name) + " is not " + (n == 4 ? "VEC4" : "VEC3") +
             " for " + ch.target_path);
    if (n == 3 && output.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
        fail(samplerWhere + ": output " + quoted("accessor", s.output, output.name) + " is not float");
    if (output.count != out.times.size() * stride)
        fail(samplerWhere + ": " + std::to_string(output.count) + " output values for " + std::to_string(out.times.size()) +
             " times (" + (stride == 3 ? "CUBICSPLINE takes three a key" : "one a key") + ")");
    const std::vector<float> flat = readFloats(s.output, n, samplerWhere + " output");
    for (size_t k = 0; k < output.count; ++k) {
        Vec4 v(flat[k * n], flat[k * n + 1], flat[k * n + 2], n == 4 ? flat[k * n + 3] : 0.f);
        if (!isFinite(v)) fail(samplerWhere + ": output value " + std::to_string(k) + " is not finite");
        const bool isValue = stride == 1 || k % 3 == 1;
        if (n == 4 && isValue && glm::dot(v, v) < 1e-12f) fail(samplerWhere + ": output value " + std::to_string(k) + " is a zero quaternion");
        if (n == 4 && isValue) v = glm::normalize(v);
        out.values.push_back(v);
    }
    return out;
}

}  // namespace rs::gltf
