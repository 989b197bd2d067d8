// The first pass's probe of the indirect kernels' scale (splat/kernel_scale.h, docs/design.md
// §7), run by splat_pass.cpp: a share of the pass's indirect photons splatted in halves at scales
// 1 and ½, from which rank 0 chooses the scale m of the passes.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "core/stats.h"
#include "output/film.h"
#include "render_context.h"
#include "splat/eye.h"
#include "splat/kernel_scale.h"
#include "splat/photons.h"
#include "splat/splat.h"
#include "splat/totals.h"

namespace rs {

class PassTargets;

// A splat's time under a time limit (none without one): lacks(s), whether under s seconds are
// left before the splat has to end (the deadline less its gather: targets.h), asked alike by
// every rank; `gather`, the seconds a gather of the receivers takes.
struct SplatTime {
    std::function<bool(double)> lacks;
    double gather = 0.0;
    // Whether the splat has to end now (after its portion).
    std::function<bool()> timeUp() const {
        if (!lacks) return nullptr;
        return [l = lacks] { return l(0.0); };
    }
};

// Under a time limit a pass is started when its steps before the splat and this share of its
// splat fit: a pass cut short still adds a whole direct film, and its photons count by their
// share (FixedFilm::photonPasses).
constexpr double kWorthStarting = 0.1;

// Half of the pass's indirect photons (KernelScaleProbe::kShare) are splatted in halves A, B at
// scale 1 and C, D at ½ (their paths split by a hash). Where the blur they measure is not clear
// (probeWidens), the rest are splatted so too and the choice is made from all of them. Each rank
// splats its share of each; the halves are summed at rank 0, which chooses the scale m and tells
// the others. The pass's own indirect light is then the probed photons' at whichever of 1 and ½
// is nearer m, and the rest's at m (until the deadline, where there is one).
class KernelScaleProbeStep {
public:
    KernelScaleProbeStep(const RenderContext& c, const PassTargets& targets, const EyePass& eye, const SplatSettings& splat,
                         SplatTotals& totals)
        : c_(c), targets_(targets), eye_(eye), splat_(splat), totals_(totals), values_(size_t(c.width) * c.height * 3) {}

    // `indirect`: the pass's indirect photons before their coverage; `other`: seconds of the
    // pass apart from their splat; `whole`: runs since the passes began. Adds their light to
    // `sum` and returns the scale chosen; `covered`: the paths whose indirect photons it splatted.
    float run(const PhotonMap& indirect, const PhotonSettings& ps, FixedFilm& sum, const Timer& whole, double other,
              const SplatTime& time, uint64_t& covered);
    // Whether the probe took all of the pass's indirect photons (probeWidens).
    bool widened() const { return widened_; }
    // With a time limit, at rank 0: the seconds a later pass needs (its part before the splat
    // and a kWorthStarting share of its splat at the scale chosen).
    double nextSeconds() const { return nextSeconds_; }
    // With a time limit where the photon rounds are chosen, at rank 0: the noises, a round's
    // splat and the seconds left (its eye pass and photon tracing are the caller's).
    const PhotonRoundsPlan& roundsPlan() const { return rounds_; }

    // Ray `index` of the first pass's photons (path order, before coverage) as that pass
    // splatted it under the probe, the scale m chosen (`widened` as the probe was): in its part
    // (the other classes, the probed photons or the rest), at that part's scale.
    static PhotonRay asSplatted(const RenderContext& c, const PhotonMap& traced, size_t index, float m, bool widened,
                                const PhotonSettings& ps);

private:
    // The halves of photons [first, last) of `indirect` at scales 1 and ½ landed in `parts` (A,
    // B, C, D) and, on sparse receivers, their `slots`; the seconds of the splats at 1 and ½.
    // With `timeUp`, in portions of whole paths (as PassTargets::splat), up to the portion during
    // which the deadline passed. Returns the end of the photons it took.
    size_t landHalves(const PhotonMap& indirect, size_t first, size_t last, const PhotonSettings& ps, FixedFilm parts[4],
                      std::vector<int64_t> slots[4], double seconds[2], const std::function<bool()>& timeUp);
    // The halves' receivers gathered into `parts`, this rank's light at each scale added to
    // `mine`, the halves summed at rank 0; `gather`: the seconds of A's gather.
    void gatherHalves(FixedFilm parts[4], std::vector<int64_t> slots[4], std::vector<int64_t> mine[2], double& gather);
    // This rank's indirect light of `part` added to `mine`, and `part`'s summed at rank 0.
    void addMine(FixedFilm& part, std::vector<int64_t>& mine);
    // A probe cut short by the deadline, `probed` of `indirect` landed in `parts` and `slots`:
    // the probed paths' light kept at 1, A and B gathered as one, after (where the time is not up)
    // the rest of the photons splatted at 1 onto the same receivers. Returns the paths covered.
    uint64_t cutShort(const PhotonMap& indirect, size_t probed, const PhotonSettings& ps, FixedFilm parts[4],
                      std::vector<int64_t> slots[4], FixedFilm& sum, const std::function<bool()>& timeUp);
    // Photons [from, n) of `indirect` at scale m, splatted into `sum` until the deadline (with
    // `sums`, their receivers' sums added there and not gathered). Returns the paths covered.
    uint64_t splatRest(const PhotonMap& indirect, size_t from, float m, const PhotonSettings& ps, FixedFilm& sum,
                       const std::function<bool()>& timeUp, std::vector<int64_t>* sums = nullptr);
    // The probed photons' light at the scale kept, into the pass.
    void keep(const std::vector<int64_t>& kept, FixedFilm& sum) const;
    // At rank 0: the probe from the summed halves, `share` the pass's indirect photons over theirs.
    KernelScaleProbe measure(const FixedFilm halves[4], double share, std::vector<float>& light) const;
    // At rank 0: the scale m of least expected error.
    double choose(const KernelScaleProbe& probe, const std::vector<float>& light, const double seconds[2], double gather,
                  const Timer& whole, double other);

    const RenderContext& c_;
    const PassTargets& targets_;
    const EyePass& eye_;
    const SplatSettings& splat_;
    SplatTotals& totals_;
    const size_t values_;
    bool widened_ = false;
    double nextSeconds_ = 0.0;
    PhotonRoundsPlan rounds_;
};

}  // namespace rs
