// glTF animations (docs/design.md §3): the node hierarchy a scene was flattened from, its
// animations' channels, and a pose — every node's local transform at one time — evaluated from
// them. Times are seconds; frame n of a walkthrough is time n / fps, as Blender's glTF exporter
// writes keys. Translations in metres, rotations unit quaternions, scales factors, all in the
// parent node's space. The loader fills SceneAnimation and checks every key (gltf_animation.cpp);
// this file only evaluates.
#pragma once

#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "core/math.h"

namespace rs {

using Quat = glm::quat;

enum class Interpolation { Step, Linear, CubicSpline };
enum class AnimatedPath { Translation, Rotation, Scale };
const char* interpolationName(Interpolation i);
const char* animatedPathName(AnimatedPath p);

// One node's local transform: translation · rotation · scale, or a matrix the file gives
// (glTF forbids animating a node with a matrix).
struct NodeTransform {
    Vec3 translation{0.f};
    Quat rotation{1.f, 0.f, 0.f, 0.f};
    Vec3 scale{1.f};
    bool hasMatrix = false;
    Mat4 matrix{1.f};
    Mat4 local() const;
};

struct AnimationChannel {
    int node = -1;
    AnimatedPath path = AnimatedPath::Translation;
    Interpolation interpolation = Interpolation::Linear;
    std::vector<float> times;  // strictly increasing
    // xyz (translation, scale) or a quaternion's xyzw, one a key; CUBICSPLINE three a key:
    // in-tangent, value, out-tangent.
    std::vector<Vec4> values;

    // The value at time t: the end values held before the first key and after the last;
    // LINEAR rotations by slerp along the shorter arc; CUBICSPLINE's Hermite spline with the
    // tangents scaled by the key interval (glTF 2.0 Appendix C); rotations normalized.
    Vec4 at(float t) const;
};

struct Animation {
    std::string name;  // as the file names it; may be empty
    std::vector<AnimationChannel> channels;
    float start = 0.f, end = 0.f;  // its first and last key's times
};

struct SceneAnimation {
    // The default scene's nodes as the file writes them (index = glTF node index).
    std::vector<int> parent;  // -1: a root (or a node outside the default scene)
    std::vector<NodeTransform> rest;
    std::vector<std::string> nodeNames;  // "node 3 'Camera'"
    std::vector<bool> movesGeometry;     // the node holds a mesh or a light
    std::vector<int> cameraNode;         // the node of Scene::cameras[i]
    std::vector<Animation> animations;
    // "skins" and "morph targets" where the file has them: rendered in their rest pose.
    std::string unsupported;

    bool animated() const { return !animations.empty(); }
    // The animations to play: all of them (`choice` empty), or the one named `choice` or with
    // that index. Throws Error(Config) naming the file when `choice` names nothing.
    std::vector<int> select(const std::string& choice, const std::string& path) const;
    // The first and the last key of the selected animations.
    float start(const std::vector<int>& selected) const;
    float end(const std::vector<int>& selected) const;
    // Whether the selected animations move only cameras: no node they animate has a mesh or a
    // light at or below it.
    bool movesOnlyCameras(const std::vector<int>& selected) const;
    // Every node's local transform at time t: the rest transforms with the selected channels
    // applied in order (a later channel on the same node and path wins).
    std::vector<Mat4> pose(const std::vector<int>& selected, float t) const;
    // A node's world transform under `local` (pose()), multiplied from the root down, in the
    // order the loader multiplies them (so that both give the same bits).
    Mat4 worldFrom(int node, const std::vector<Mat4>& local) const;
};

// The camera `rest` placed at world transform `world`: position, forward (−Z), right and up;
// name, field of view and aspect kept: as GltfLoader::addCamera places a camera, which a test
// checks bit for bit.
struct Camera;
Camera placeCamera(const Camera& rest, const Mat4& world);

}  // namespace rs
