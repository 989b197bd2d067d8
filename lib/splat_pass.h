// The passes of photon ray splatting (docs/design.md §4, §7–9): each one's eye pass, the
// receivers and occlusion trees over its eye samples, its photons and their splat, and the first
// pass's probe of the indirect kernels' scale (§7). render.cpp decides which passes run, where
// and until when; this file what one pass does, in order.
#pragma once

#include <functional>
#include <memory>

#include "core/staged_files.h"
#include "grid/occlusion_grid.h"
#include "output/film.h"
#include "render_context.h"
#include "splat/coverage.h"
#include "splat/eye.h"
#include "splat/photons.h"
#include "splat/splat.h"

namespace rs {

class PassTargets;

// Figures summed over a render's passes (the last pass's sizes are reported as they come).
struct SplatTotals {
    SplatStats splat;
    CoverageStats coverage;
    int64_t photonsStored = 0;
    double photonMb = 0.0;
};

class SplatPasses {
public:
    // Builds the occlusion grid (or its empty twin) once, and every stage's settings.
    SplatPasses(const RenderContext& c, StagedFiles* outputs);

    // Pass `share.pass`, this rank's share of it, into `sum`: the eye pass's own light, then the
    // photons', until `deadline` where there is one (sum.photonPasses counts the share of each
    // class's photons splatted). Returns the seconds a later pass needs to be worth starting: its
    // steps before the splat and a tenth of a whole splat.
    double render(const PassShare& share, FixedFilm& sum, const Deadline& deadline);
    // --photon PASS:INDEX: that ray's light alone into `sum`, after the first pass where that pass
    // chooses the kernel scale (docs/design.md §9).
    void replay(FixedFilm& sum);

    bool probing() const { return probing_; }
    // With a time limit, at rank 0, after the first pass: the seconds a later pass needs.
    const double* nextSeconds() const { return &nextPass_; }

private:
    EyePass traceEye(int pass);
    float receiverSpacing(int pass) const;
    PhotonMap tracePhotonsOf(int pass, PhotonSettings& passSettings);
    double splatPass(int pass, const PassShare& share, PassTargets& targets, const EyePass& eye, PhotonMap photons,
                     const PhotonSettings& passSettings, FixedFilm& sum, const Deadline& deadline);
    std::function<bool()> timeUpFor(const PassShare& share, const Deadline& deadline) const;
    void replayRay(PhotonMap& photons, const PhotonSettings& passSettings);
    void report();

    const RenderContext& c_;
    OcclusionGrid grid_;
    EyePassSettings eye_;
    PhotonSettings photons_;
    CoverageSettings coverage_;
    SplatSettings splat_;
    SplatTotals totals_;
    const bool probing_, sparse_, measuresCoverage_;
    bool replaying_ = false;
    double nextPass_ = 0.0;  // the probe's estimate of a later pass's seconds
    Timer whole_;
};

}  // namespace rs
