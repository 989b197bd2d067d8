// A walkthrough (docs/usage.md "Animations and walkthroughs"): frames cfg.firstFrame..lastFrame
// of the file's animations, frame n posed at time n / fps (scene/animation.h), each rendered as
// a still of its pose and written to its own outputs as soon as it is done.
//
// What is kept across the range: with only cameras moving, the scene as loaded, everything
// render.cpp's PreparedScene builds from it (threads, BVH, lights) and, for the splat methods,
// every pass's photons (PhotonStore, docs/design.md §12), each frame changing only the camera;
// otherwise each frame loads and flattens its own pose. Each frame's passes use the render's
// seed, not the frame's place in the range, and a frame rendered alone has a store of its own:
// frame f is the same image alone or in any range.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "config.h"
#include "core/log.h"
#include "ranks.h"
#include "render.h"
#include "scene/scene.h"

namespace rs {

// Frame `frame`'s file for output `pattern` (Blender's convention): the last run of '#' in its
// file name becomes the frame number, zero-padded to the run's length (walk_####.exr →
// walk_0024.exr); with no '#' and `several` frames, "_" and four digits go before the extension
// (walk.exr → walk_0024.exr); else the pattern as it is.
std::string framePath(const std::string& pattern, int frame, bool several);

class Walkthrough {
public:
    // Loads cfg.scene and chooses its animations (cfg.animation); warns where frames fall outside
    // them and about skins and morph targets. Throws Error naming the file.
    Walkthrough(const RenderConfig& cfg, Reporter& reporter, Ranks& ranks);
    ~Walkthrough();

    // Renders the range in order, writing each frame's outputs when it is done (rank 0); frames
    // whose outputs all exist are skipped with cfg.skipExisting. Returns the frames rendered.
    int run();
    // Frame `frame` rendered, not written.
    RenderResult renderFrame(int frame);
    // cfg with frame `frame`'s output files.
    RenderConfig frameConfig(int frame) const;
    bool movesOnlyCameras() const { return camerasOnly_; }
    const Scene& restScene() const { return rest_; }

private:
    Camera cameraAt(const std::vector<Mat4>& pose) const;

    const RenderConfig& cfg_;
    Reporter& reporter_;
    Ranks& ranks_;
    Scene rest_;  // as the file writes it: its animations, and the geometry of a cameras-only range
    std::vector<int> selected_;  // the animations that play
    bool camerasOnly_ = true;
    int cameraIndex_ = -1;  // the rendered camera in Scene::cameras; -1: the framing camera
    // The range's state, kept from frame to frame where only cameras move: the scene's setup
    // and the photons of every pass.
    std::unique_ptr<PreparedScene> prepared_;
    std::unique_ptr<PhotonStore> store_;
};

}  // namespace rs
