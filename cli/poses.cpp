// `raysplat info --frames` (poses.h).
#include "poses.h"

#include <cstdio>

#include "core/error.h"
#include "core/stats.h"
#include "scene/animation.h"
#include "walkthrough.h"

namespace rs::cli {

namespace {

std::string number(float v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.9g", v + 0.f);  // no "-0"
    return b;
}

std::string array(const Vec3& v) { return "[" + number(v.x) + ", " + number(v.y) + ", " + number(v.z) + "]"; }

std::string array(const Mat4& m) {
    std::string s = "[";
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) s += number(m[c][r]) + (c == 3 && r == 3 ? "]" : ", ");
    return s;
}

// Each primitive's world bounds ("objects", Scene::objectNames) in `scene`'s triangles.
std::string objectBounds(const Scene& scene) {
    std::vector<Vec3> lo(scene.objectNames.size(), Vec3(kInf)), hi(scene.objectNames.size(), Vec3(-kInf));
    for (size_t t = 0; t < scene.triObject.size(); ++t)
        for (int v = 0; v < 3; ++v) {
            lo[scene.triObject[t]] = glm::min(lo[scene.triObject[t]], scene.positions[3 * t + v]);
            hi[scene.triObject[t]] = glm::max(hi[scene.triObject[t]], scene.positions[3 * t + v]);
        }
    std::string s;
    for (size_t o = 0; o < lo.size(); ++o)
        s += std::string(o ? ", " : "") + "{\"name\": " + jsonString(scene.objectNames[o]) + ", \"lo\": " + array(lo[o]) +
             ", \"hi\": " + array(hi[o]) + "}";
    return s;
}

}  // namespace

void printPoses(SceneFile& file, const RenderConfig& q) {
    const SceneAnimation a = file.scene().animation;  // posing replaces the file's scene
    const std::vector<int> selected = a.select(q.animation, file.scene().path);
    const int cameraIndex = file.scene().cameraIndex(q.camera);
    // Where only cameras move, the walkthrough renders the triangles as read, the camera placed
    // by the pose; else the scene flattened at each frame's pose, with its camera.
    const bool camerasOnly = a.movesOnlyCameras(selected);
    const std::string restObjects = camerasOnly ? objectBounds(file.scene()) : "";
    for (int frame = q.firstFrame; frame <= q.lastFrame; frame += q.frameStep) {
        const float t = frameTime(frame, q.fps);
        const std::vector<Mat4> pose = a.pose(selected, t);
        const Scene* posed = camerasOnly ? nullptr : &file.pose(pose);
        const Camera cam = posed ? posed->camera(q.camera) : posedCamera(file.scene(), cameraIndex, q.camera, pose);
        std::string line = "{\"frame\": " + std::to_string(frame) + ", \"time\": " + number(t) + ", \"camera\": {\"name\": " +
                           jsonString(cam.name) + ", \"position\": " + array(cam.position) + ", \"forward\": " +
                           array(cam.forward) + ", \"up\": " + array(cam.up) + ", \"right\": " + array(cam.right) +
                           ", \"yfov\": " + number(cam.yfov) + "}, \"nodes\": [";
        for (size_t n = 0; n < pose.size(); ++n)
            line += std::string(n ? ", " : "") + "{\"index\": " + std::to_string(n) + ", \"node\": " + jsonString(a.nodeNames[n]) +
                    ", \"world\": " + array(a.worldFrom(int(n), pose)) + "}";
        std::printf("%s], \"objects\": [%s]}\n", line.c_str(), (posed ? objectBounds(*posed) : restObjects).c_str());
    }
}

}  // namespace rs::cli
