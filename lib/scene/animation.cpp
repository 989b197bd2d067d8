// Evaluating glTF animations (animation.h).
#include "scene/animation.h"

#include <algorithm>

#include "core/error.h"
#include "scene/scene.h"

namespace rs {

const char* interpolationName(Interpolation i) {
    switch (i) {
        case Interpolation::Step: return "STEP";
        case Interpolation::Linear: return "LINEAR";
        case Interpolation::CubicSpline: return "CUBICSPLINE";
    }
    return "?";
}

const char* animatedPathName(AnimatedPath p) {
    switch (p) {
        case AnimatedPath::Translation: return "translation";
        case AnimatedPath::Rotation: return "rotation";
        case AnimatedPath::Scale: return "scale";
    }
    return "?";
}

Mat4 NodeTransform::local() const {
    if (hasMatrix) return matrix;
    // The loader's order and rounding: T · R · S.
    return glm::translate(Mat4(1.f), translation) * glm::mat4_cast(rotation) * glm::scale(Mat4(1.f), scale);
}

namespace {

Quat quatOf(const Vec4& v) { return Quat(v.w, v.x, v.y, v.z); }
Vec4 vecOf(const Quat& q) { return Vec4(q.x, q.y, q.z, q.w); }

}  // namespace

Vec4 AnimationChannel::at(float t) const {
    const bool cubic = interpolation == Interpolation::CubicSpline;
    const int stride = cubic ? 3 : 1, valueAt = cubic ? 1 : 0;
    const size_t keys = times.size();
    auto value = [&](size_t k) { return values[k * stride + valueAt]; };
    // The end values are held outside the keys.
    if (keys == 1 || t <= times.front()) return value(0);
    if (t >= times.back()) return value(keys - 1);
    const size_t k1 = size_t(std::upper_bound(times.begin(), times.end(), t) - times.begin());
    const size_t k0 = k1 - 1;
    if (interpolation == Interpolation::Step) return value(k0);
    const float td = times[k1] - times[k0];
    const float s = (t - times[k0]) / td;
    const bool rotation = path == AnimatedPath::Rotation;
    if (!cubic) {
        if (!rotation) return glm::mix(value(k0), value(k1), s);
        // Slerp along the shorter arc: q and −q are the same rotation.
        Quat a = quatOf(value(k0)), b = quatOf(value(k1));
        if (glm::dot(a, b) < 0.f) b = -b;
        return vecOf(glm::normalize(glm::slerp(a, b, s)));
    }
    // glTF 2.0 Appendix C: the Hermite spline between the keys' values, its tangents the
    // first key's out-tangent and the second's in-tangent, each times the interval.
    const float s2 = s * s, s3 = s2 * s;
    const Vec4 out0 = values[k0 * 3 + 2], in1 = values[k1 * 3 + 0];
    Vec4 v = (2.f * s3 - 3.f * s2 + 1.f) * value(k0) + td * (s3 - 2.f * s2 + s) * out0 +
             (-2.f * s3 + 3.f * s2) * value(k1) + td * (s3 - s2) * in1;
    if (rotation) v = vecOf(glm::normalize(quatOf(v)));
    return v;
}

std::vector<int> SceneAnimation::select(const std::string& choice, const std::string& path) const {
    std::vector<int> all;
    if (choice.empty()) {
        for (int a = 0; a < int(animations.size()); ++a) all.push_back(a);
        return all;
    }
    for (int a = 0; a < int(animations.size()); ++a)
        if (animations[a].name == choice) return {a};
    const bool digits = !choice.empty() && std::all_of(choice.begin(), choice.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (digits && choice.size() < 10 && std::stoi(choice) < int(animations.size())) return {std::stoi(choice)};
    throw Error(ErrorKind::Config, path + ": `animation` " + choice + ": no animation has that name or index (the file has " +
                                       std::to_string(animations.size()) + ")");
}

float SceneAnimation::start(const std::vector<int>& selected) const {
    float t = selected.empty() ? 0.f : animations[selected[0]].start;
    for (int a : selected) t = std::min(t, animations[a].start);
    return t;
}

float SceneAnimation::end(const std::vector<int>& selected) const {
    float t = 0.f;
    for (int a : selected) t = std::max(t, animations[a].end);
    return t;
}

bool SceneAnimation::movesOnlyCameras(const std::vector<int>& selected) const {
    // A node moves geometry when it or a node below it holds a mesh or a light.
    std::vector<bool> below(movesGeometry);
    for (int n = 0; n < int(parent.size()); ++n)
        if (movesGeometry[n])
            for (int p = parent[n], depth = 0; p >= 0 && depth < 257; p = parent[p], ++depth) below[p] = true;
    for (int a : selected)
        for (const AnimationChannel& c : animations[a].channels)
            if (below[c.node]) return false;
    return true;
}

std::vector<Mat4> SceneAnimation::pose(const std::vector<int>& selected, float t) const {
    std::vector<NodeTransform> nodes = rest;
    for (int a : selected)
        for (const AnimationChannel& c : animations[a].channels) {
            const Vec4 v = c.at(t);
            NodeTransform& n = nodes[c.node];
            switch (c.path) {
                case AnimatedPath::Translation: n.translation = Vec3(v); break;
                case AnimatedPath::Rotation: n.rotation = quatOf(v); break;
                case AnimatedPath::Scale: n.scale = Vec3(v); break;
            }
        }
    std::vector<Mat4> local(nodes.size());
    for (size_t n = 0; n < nodes.size(); ++n) local[n] = nodes[n].local();
    return local;
}

Mat4 SceneAnimation::worldFrom(int node, const std::vector<Mat4>& local) const {
    std::vector<int> chain;
    for (int n = node; n >= 0 && chain.size() < 258; n = parent[n]) chain.push_back(n);
    Mat4 world(1.f);
    for (auto n = chain.rbegin(); n != chain.rend(); ++n) world = world * local[*n];
    return world;
}

Camera placeCamera(const Camera& rest, const Mat4& world) {
    Camera cam = rest;
    cam.position = Vec3(world[3]);
    cam.forward = glm::normalize(-Vec3(world[2]));
    cam.right = glm::normalize(glm::cross(cam.forward, Vec3(world[1])));
    cam.up = glm::cross(cam.right, cam.forward);
    return cam;
}

}  // namespace rs
