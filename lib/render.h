// The whole pipeline on one page (docs/design.md §1): render() calls the stages in order.
#pragma once

#include <memory>

#include "config.h"
#include "core/staged_files.h"
#include "output/film.h"
#include "core/log.h"
#include "ranks.h"
#include "scene/scene.h"
#include "core/stats.h"

namespace rs {

struct RenderResult {
    Film film;
    Stats stats;
    ImageAttributes attributes;  // config + timings, for the EXR header
    // Files written during the render (the --vdb grid), committed by writeOutputs together
    // with the images, removed if the result is dropped.
    std::shared_ptr<StagedFiles> outputs = std::make_shared<StagedFiles>();
};

struct PhotonStore;  // splat_pass.h

// With several ranks (an MPI job, lib/ranks.h) every rank calls it alike; rank 0's result holds
// the image, the others' film is empty. With a photon store (the frames of a walkthrough whose
// scene does not move, docs/design.md §12) the splat's photons come from it and are kept in it.
RenderResult render(const Scene& scene, const RenderConfig& cfg, Reporter& reporter, Ranks& ranks = singleProcess(),
                    PhotonStore* store = nullptr);

// What a render builds from the scene before the camera matters — the memory check, the
// threads, the BVH, the environment and the lights — kept for any number of views of the same
// scene: a walkthrough's frames where only the camera moves (lib/walkthrough.h). `scene` must
// outlive it; every view must have the aspect of cfg's camera (the image size is fixed here).
class PreparedScene {
public:
    // `keepsPhotons`: a walkthrough's, whose photons are kept for its frames (memory.h).
    PreparedScene(const Scene& scene, const RenderConfig& cfg, Reporter& reporter, Ranks& ranks, bool keepsPhotons = false);
    ~PreparedScene();
    // The image through `camera`: the same bits as render() with the scene's camera there (and
    // the same store).
    RenderResult render(const Camera& camera, PhotonStore* store = nullptr);
    int views() const { return views_; }

private:
    struct Parts;
    std::unique_ptr<Parts> parts_;
    int views_ = 0;
};

// EXR (+ PNG, + stats JSON) as the config asks, each written atomically.
void writeOutputs(RenderResult& result, const RenderConfig& cfg);

// The version string of this build.
const char* versionString();

}  // namespace rs
