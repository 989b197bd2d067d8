// The passes of photon ray splatting (docs/design.md §4, §7–9): each one's eye pass, the
// receivers and occlusion trees over its eye samples, its photons and their splat, and the first
// pass's probe of the indirect kernels' scale (§7). render.cpp decides which passes run, where
// and until when; this file what one pass does, in order.
#pragma once

#include <functional>
#include <map>
#include <memory>

#include "core/staged_files.h"
#include "grid/occlusion_grid.h"
#include "output/film.h"
#include "render_context.h"
#include "splat/coverage.h"
#include "splat/eye.h"
#include "splat/kernel_scale.h"
#include "splat/photons.h"
#include "splat/splat.h"
#include "splat/totals.h"

namespace rs {

class PassTargets;
struct SplatTime;

// The photons of a walkthrough's passes, kept across its frames (docs/design.md §12): a pass's
// photons are traced once, with every kernel's coverage measured, and splatted into each frame
// that renders that pass. They depend on the scene and the settings, not on the camera, so a
// frame's image is the same whether its photons were traced for it or for a frame before it.
struct PhotonStore {
    std::map<int, PhotonMap> passes;  // by round: pass × RenderConfig::kMaxPhotonRounds + round
    // The occlusion grid (or its empty twin) the first frame built: it depends on the scene alone.
    std::shared_ptr<const OcclusionGrid> grid;
    int64_t traced = 0;               // rounds traced (the rest of the frames' rounds reused them)
    double bytes() const {
        double b = 0.0;
        for (const auto& [pass, photons] : passes) b += double(photons.bytes());
        return b;
    }
};

class SplatPasses {
public:
    // Builds the occlusion grid (or its empty twin) once, and every stage's settings. With a
    // store, photons come from it (and are added to it): the kernel scale is not probed then,
    // since a probe would tie the photons to the frame that measured it.
    SplatPasses(const RenderContext& c, StagedFiles* outputs, PhotonStore* store = nullptr);

    // Pass `share.pass`, this rank's share of it, into `sum`: the eye pass's own light, then the
    // photons', until `deadline` where there is one (sum.photonPasses counts the share of each
    // class's photons splatted). Returns the seconds a later pass needs to be worth starting: its
    // steps before the splat and a tenth of a whole splat.
    double render(const PassShare& share, FixedFilm& sum, const Deadline& deadline);
    // --photon PASS:INDEX: that ray's light alone into `sum`, after the first pass where that pass
    // chooses the kernel scale (docs/design.md §9).
    void replay(FixedFilm& sum);

    // Under a time limit, where no whole pass fits the time left: pass `pass`'s direct film
    // alone into `sum` (no eye samples, photons or splat: docs/design.md §9). Returns its seconds.
    double renderFilm(int pass, FixedFilm& sum);
    bool filmOnly() const { return eye_.directSpp > 0; }
    // The last pass's eye pass seconds (a film pass takes less).
    const double* eyeSeconds() const { return &eyeSeconds_; }

    bool probing() const { return probing_; }
    // With a time limit, at rank 0, after the first pass: the seconds a later pass needs.
    const double* nextSeconds() const { return &nextPass_; }

private:
    EyePass traceEye(int pass, const Deadline& deadline);
    EyePassSize firstEyePass(const Deadline& deadline) const;
    // The share of the time left that the first pass's eye pass may take under a time limit.
    static constexpr double kFirstEyeShare = 0.5;
    // The film samples beyond D that pass `pass` takes a pixel: the first pass's choice, from pass 1 on.
    const std::vector<uint16_t>* extraFilmOf(int pass) const { return pass > 0 && !extraFilm_.empty() ? &extraFilm_ : nullptr; }
    float receiverSpacing(int pass) const;
    PhotonMap tracePhotonsOf(int pass, int round, PhotonSettings& passSettings);
    PhotonMap storedPhotonsOf(int pass, int round, PhotonSettings& passSettings);
    // The photon rounds of pass `pass` (docs/design.md §9), and their choice under a time limit.
    int roundsOf(int pass) const;
    int chooseRounds(PhotonRoundsPlan plan, double photonsBefore);
    // `sums`: where the indirect photons' receivers' sums wait for the pass's gather (rounds).
    double splatPass(int pass, int round, const PassShare& share, PassTargets& targets, const EyePass& eye, PhotonMap photons,
                     const PhotonSettings& passSettings, FixedFilm& sum, const SplatTime& time, std::vector<int64_t>* sums);
    std::function<bool(double)> lacksFor(const PassShare& share, const Deadline& deadline) const;
    void replayRay(PhotonMap& photons, const PhotonSettings& passSettings);
    void report();

    const RenderContext& c_;
    PhotonStore* store_;
    std::shared_ptr<const OcclusionGrid> grid_;  // the store's where there is one
    EyePassSettings eye_;
    std::vector<uint16_t> extraFilm_;  // the passes' film samples beyond D a pixel, from the first pass
    PhotonSettings photons_;
    CoverageSettings coverage_;
    SplatSettings splat_;
    SplatTotals totals_;
    const bool probing_, sparse_, measuresCoverage_;
    bool replaying_ = false;
    int traced_ = 0;  // rounds (passes) whose photons this render traced (stats: photon_passes_traced)
    double nextPass_ = 0.0;  // the probe's estimate of a later pass's seconds
    bool probeWidened_ = false;  // the first pass probed all its indirect photons (kernel_probe.h)
    int rounds_ = 1;         // the photon rounds of the passes after the first, where it chooses them
    double eyeAndTrees_ = 0.0, photonsBegan_ = 0.0;  // the first pass's: seconds, and whole_'s at its photons
    double eyeSeconds_ = 0.0;
    Timer whole_;
};

}  // namespace rs
