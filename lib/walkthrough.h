// A walkthrough (docs/usage.md "Animations and walkthroughs"): frames cfg.firstFrame..lastFrame
// of the file's animations, frame n posed at time n / fps (scene/animation.h), each rendered as
// a still of its pose and written to its own outputs as soon as it is done.
//
// What is kept across the range: the file as read (SceneFile: parsed, materials, decoded
// textures, lights, animations). With only cameras moving, also the scene as flattened,
// everything render.cpp's PreparedScene builds from it (threads, BVH, lights) and, for the
// splat methods, every pass's photons (PhotonStore, docs/design.md §12), each frame changing
// only the camera. Where a mesh or light moves, each frame flattens the nodes at its pose and
// builds what depends on the geometry (BVH, lights, grid, photons) for itself. Each frame's
// passes use the render's seed, not the frame's place in the range, and a frame rendered alone
// has a store of its own: frame f is the same image alone or in any range.
//
// Under MPI (lib/ranks.h) a range of at least as many frames as ranks is dealt out whole: in
// round k rank r renders frame firstFrame + k·R + r by itself and writes it, and rank 0 reports
// the round. Fewer frames than ranks: every frame is divided between the ranks as a still is.
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

// Frame `frame`'s time, frame / fps seconds, as every frame is posed.
inline float frameTime(int frame, float fps) { return float(frame) / fps; }

// The camera a frame renders where only cameras move: camera `index` of `rest` (its
// Scene::cameraIndex) placed by `pose` (SceneAnimation::pose); the framing camera (index < 0,
// `which` as --camera gives it) does not move.
Camera posedCamera(const Scene& rest, int index, const std::string& which, const std::vector<Mat4>& pose);

class Walkthrough {
public:
    // Reads cfg.scene and chooses its animations (cfg.animation); warns where frames fall outside
    // them and about skins and morph targets. Throws Error naming the file.
    Walkthrough(const RenderConfig& cfg, Reporter& reporter, Ranks& ranks);
    ~Walkthrough();

    // Renders the range in order (by rounds of whole frames under MPI), writing each frame's
    // outputs when it is done; frames whose outputs all exist are skipped with cfg.skipExisting.
    // Returns the frames the job rendered (at rank 0).
    int run();
    // Frame `frame` rendered, not written.
    RenderResult renderFrame(int frame);
    // cfg with frame `frame`'s output files.
    RenderConfig frameConfig(int frame) const;
    bool movesOnlyCameras() const { return camerasOnly_; }
    bool dealsWholeFrames() const { return wholeFrames_; }
    // The file's scene: its animations, and the geometry of the pose flattened last.
    const Scene& scene() const { return file_->scene(); }

private:
    // What became of one frame of a round (four integers, summed at rank 0 by the round).
    struct FrameDone {
        enum Status : int64_t { kNone = 0, kRendered = 1, kSkipped = 2 };  // kNone: no frame for this rank
        int64_t status = kNone, width = 0, height = 0, microseconds = 0;
    };
    FrameDone doFrame(int frame, int left, double secondsLeft);
    void reportRound(int firstOfRound, const std::vector<int64_t>& done);
    Ranks& frameRanks() { return alone_ ? *alone_ : ranks_; }

    const RenderConfig& cfg_;
    RenderConfig posedCfg_;  // cfg_ for the frames where meshes or lights move
    Reporter& reporter_;
    Ranks& ranks_;
    std::unique_ptr<Ranks> alone_;  // this rank rendering a whole frame by itself; null: ranks_ split each frame
    bool wholeFrames_ = false;
    std::unique_ptr<SceneFile> file_;
    double readSeconds_ = 0.0;  // reading the file, counted in the first frame's stats
    bool firstFrame_ = true;
    std::vector<int> selected_;  // the animations that play
    bool camerasOnly_ = true;
    int cameraIndex_ = -1;  // the rendered camera in Scene::cameras; -1: the framing camera
    // The range's state, kept from frame to frame where only cameras move: the scene's setup
    // and the photons of every pass.
    std::unique_ptr<PreparedScene> prepared_;
    std::unique_ptr<PhotonStore> store_;
};

}  // namespace rs
