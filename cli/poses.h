// `raysplat info SCENE --frames A-B`: the pose of each frame of a walkthrough as data, for
// programs that check it against another tool (scripts/blender_animation_check.py).
#pragma once

#include <string>

#include "config.h"
#include "scene/scene.h"

namespace rs::cli {

// One JSON object a line on stdout for each frame of cfg's walkthrough (frames, frame step, fps,
// animation, camera): its number and time, the camera a render of that frame uses (position, forward, up, right, yfov in radians) and the world matrix of
// every node of the default scene (column-major, glTF's axes and metres), and each primitive's
// world bounds ("objects": the triangles a render of the frame uses, flattened at the frame's
// pose where meshes move), placed as a walkthrough places them: frame n at time n / fps.
void printPoses(SceneFile& file, const RenderConfig& cfg);

}  // namespace rs::cli
