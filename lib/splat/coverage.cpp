// Kernel coverage (docs/design.md §8): Embree probes along each photon's kernel disc, a packet a
// photon, in parallel over the photons; each photon's numbers depend only on (seed, pass, index).
#include "splat/coverage.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "core/log.h"
#include "core/parallel.h"
#include "core/sampling.h"
#include "core/stats.h"
#include "scene/accel.h"
#include "splat/eye.h"
#include "splat/photons.h"

namespace rs {

namespace {

// Surfaces a probe follows at most, a bound on its work: a line crosses more only through rows of
// thin parts, and most of those crossings are hidden from x(i−1) by the ones before them.
constexpr int kMaxCrossings = 8;
constexpr float kGoldenTurn = 0.38196601f;  // 2 − φ: successive probes a golden angle apart

// What coverageOf found, for kernelEdges: each probe's offset in the disc's frame (Frame(ray.dir),
// in radii) and whether it arrived; the points where probes arrived and their surfaces' normals.
struct ProbeRecord {
    static constexpr int kMaxPoints = 32;
    float x[RayAccel::kPacket], y[RayAccel::kPacket];
    bool arrived[RayAccel::kPacket];
    int count = 0;
    bool overflow = false;
    Vec3 at[kMaxPoints], normal[kMaxPoints];
    void arrive(int probe, const Vec3& p, const Vec3& n) {
        arrived[probe] = true;
        if (count == kMaxPoints) overflow = true;
        else at[count] = p, normal[count++] = n;
    }
};

// The share of one photon ray's kernel that lands on a receiving surface. Probe k follows the
// disc ray at radius h·√s_k, where s_k = 1 − (1 − (k + ½)/n)^⅓ inverts the biweight kernel's
// radial distribution (its mass inside s = d²/h² is 1 − (1 − s)³), so each probe carries an
// equal share of the kernel's weight; successive probes turn by the golden angle. A probe starts
// where its ray crosses the tangent plane of the surface the photon leaves (rule 1), or at the
// origin's depth, and ends with the cylinder. Like the splat, which takes every sample in the
// cylinder and not only the first along each line, it counts every non-specular surface it
// crosses whose point, lifted to the side the probe comes from, sees x(i−1) (rule 2), and,
// `windowed`, lies within the ray's receiver window (PhotonRay::kernelBegin and kernelEnd), as
// the splat's samples must. The probes of a photon are parallel: one packet a crossing; their
// rule-2 rays share an end, and are asked in full packets after the last crossing.
float coverageOf(const RayAccel& accel, const PhotonRay& ray, int probes, float turn, bool windowed, ProbeRecord* record = nullptr) {
    const Frame frame(ray.dir);
    const Vec3 n = ray.originNormal ? decodeUnit(ray.originNormal) : Vec3(0.f);
    const float cosOrigin = glm::dot(n, ray.dir);
    const float begin = ray.kernelBegin(windowed), end = ray.kernelEnd(windowed);
    const float offset = 2.f * rayOriginOffset(ray.origin);
    const Scene& scene = accel.scene();
    Vec3 from[RayAccel::kPacket];
    float left[RayAccel::kPacket], t[RayAccel::kPacket], depth[RayAccel::kPacket];
    uint32_t tri[RayAccel::kPacket];
    int probe[RayAccel::kPacket];  // the probe of each ray
    // The points rule 2 asks about, of every crossing: whether one sees x(i−1) does not change
    // where its probe goes on, so they are asked together, in full packets, once the probes end.
    constexpr int kMaxLifted = RayAccel::kPacket * kMaxCrossings;
    Vec3 lifted[kMaxLifted], liftedNormal[kMaxLifted];
    int liftedProbe[kMaxLifted];
    int receivers = 0;
    int live = 0;
    for (int k = 0; k < probes; ++k) {
        const float s = 1.f - std::cbrt(1.f - (float(k) + 0.5f) / float(probes));
        const float phi = 2.f * kPi * (turn + float(k) * kGoldenTurn);
        const float x = std::sqrt(s) * std::cos(phi), y = std::sqrt(s) * std::sin(phi);
        if (record) record->x[k] = x, record->y[k] = y, record->arrived[k] = 0;
        const Vec3 u = ray.radius * (x * frame.s + y * frame.t);
        float start = cosOrigin > 1e-3f ? std::max(0.f, -glm::dot(u, n) / cosOrigin) : 0.f;
        start += offset / std::max(cosOrigin, 0.05f);
        start = std::max(start, begin);  // what lies before the window counts for nothing
        if (!(start < end)) continue;
        from[live] = ray.origin + u + start * ray.dir;
        probe[live] = k;
        depth[live] = start;
        left[live++] = end - start;
    }
    for (int crossing = 0; crossing < kMaxCrossings && live > 0; ++crossing) {
        const uint32_t hits = accel.intersectParallel(from, live, ray.dir, left, t, tri);
        int next = 0;
        for (int i = 0; i < live; ++i) {
            if (!(hits >> i & 1u)) continue;
            const Vec3 p = from[i] + t[i] * ray.dir;
            const Vec3 ng = scene.geometricNormal(tri[i]);
            const float eps = rayOriginOffset(p);
            const Vec3 toward = glm::dot(ray.dir, ng) < 0.f ? ng : -ng;  // the side the probe comes from
            const float at = depth[i] + t[i];
            if (at > begin && !scene.materials[scene.triMaterial[tri[i]]].isSpecular()) {
                liftedNormal[receivers] = ng;
                liftedProbe[receivers] = probe[i], lifted[receivers++] = p + eps * toward;
            }
            if (left[i] - t[i] > 0.f) from[next] = p - eps * toward, probe[next] = probe[i], depth[next] = at, left[next++] = left[i] - t[i];
        }
        live = next;
    }
    int covered = 0;
    for (int first = 0; first < receivers; first += RayAccel::kPacket) {
        const int n = std::min(RayAccel::kPacket, receivers - first);
        const uint32_t hidden = accel.occludedToPoint(lifted + first, n, ray.origin);
        covered += n - __builtin_popcount(hidden);
        if (record)
            for (int i = 0; i < n; ++i)
                if (!(hidden >> i & 1u)) record->arrive(liftedProbe[first + i], lifted[first + i], liftedNormal[first + i]);
    }
    return float(covered) / float(probes);
}

// The lines across a photon's kernel disc (KernelEdge) where it lands on one plane, the one its
// ray hits: every probe that arrives, arrives on it. Returns the share of the kernel that neither
// line accounts for, which the photon's flux is divided by (1: the lines account for all of it),
// or −1 where the kernel does not land on one plane, or rule 1 has no plane to cut it with.
//  • Rule 1, exact on a plane: the disc ray at offset z ⊥ ω starts where it crosses the origin's
//    tangent plane (normal n_o), at depth −z·n_o / (n_o·ω), and meets the hit's plane (normal
//    n_h, facing the photon) at length − z·n_h / (n_h·ω): it arrives where z·a < length, with
//    a = n_h / (n_h·ω) − n_o / (n_o·ω), which cuts the disc where |a⊥|·h > length.
//  • The probes that miss on rule 1's arriving side (past a convex edge, a hole, a window's end):
//    a line across the direction from their mean to the mean of those that arrive, where it
//    leaves the share of rule 1's side that arrives on its own arriving side, kept only where it
//    parts them; else the flux is divided by that share, as without lines.
float kernelEdges(const RayAccel& accel, const PhotonRay& ray, const ProbeRecord& record, int probes, float coverage,
                  KernelEdge& edge) {
    edge.lines = 0;
    if (!ray.originNormal || record.overflow) return -1.f;
    const Vec3 no = decodeUnit(ray.originNormal);
    const float cosO = glm::dot(no, ray.dir);
    SurfacePoint hit;
    float t = 0.f;
    const Vec3 from = ray.origin + (2.f * rayOriginOffset(ray.origin) / std::max(cosO, 0.05f)) * ray.dir;
    if (!(cosO > 1e-3f) || !accel.intersect(from, ray.dir, ray.length * 1.01f + 1e-4f, hit, t)) return -1.f;
    const Vec3 nh = glm::dot(hit.ng, ray.dir) < 0.f ? hit.ng : -hit.ng;
    const float cosH = glm::dot(nh, ray.dir);
    const float tolerance = KernelEdge::kPlaneTolerance * ray.radius + 4.f * rayOriginOffset(hit.p);
    for (int k = 0; k < record.count; ++k)
        if (std::abs(glm::dot(record.at[k] - hit.p, nh)) > tolerance || std::abs(glm::dot(record.normal[k], nh)) < KernelEdge::kPlaneCos)
            return -1.f;
    if (!(cosH < -1e-3f)) return -1.f;
    const Frame frame(ray.dir);
    const Vec3 a = nh / cosH - no / cosO;
    const float ax = glm::dot(a, frame.s) * ray.radius, ay = glm::dot(a, frame.t) * ray.radius;  // in radii
    const float across = std::sqrt(ax * ax + ay * ay);
    const bool rule1 = across > ray.length;
    if (rule1) {
        edge.e[0] = -(ax * frame.s + ay * frame.t) / (across * ray.radius);
        edge.t0[0] = ray.length / across;
        edge.lines = 1;
    }
    const auto kept = [&](int k) { return !rule1 || record.x[k] * ax + record.y[k] * ay < ray.length; };
    float sx = 0.f, sy = 0.f, mx = 0.f, my = 0.f;
    int arrived = 0, missed = 0;
    for (int k = 0; k < probes; ++k) {
        if (!kept(k)) continue;
        if (record.arrived[k]) sx += record.x[k], sy += record.y[k], ++arrived;
        else mx += record.x[k], my += record.y[k], ++missed;
    }
    // The share of rule 1's arriving side that arrives: from the probes on that side, which are
    // distributed as the kernel there (the coverage over rule 1's share would scatter about 1).
    const float rest = rule1 ? (arrived + missed > 0 ? float(arrived) / float(arrived + missed) : 1.f) : coverage;
    if (arrived == 0 || missed == 0) return rest;
    const float dx = sx / float(arrived) - mx / float(missed), dy = sy / float(arrived) - my / float(missed);
    const float len = std::sqrt(dx * dx + dy * dy);
    if (!(len > 0.f)) return rest;
    float lastMissed = -1.f, firstArrived = 1.f;
    for (int k = 0; k < probes; ++k) {
        if (!kept(k)) continue;
        const float along = (record.x[k] * dx + record.y[k] * dy) / len;
        if (record.arrived[k]) firstArrived = std::min(firstArrived, along);
        else lastMissed = std::max(lastMissed, along);
    }
    if (!(lastMissed < firstArrived)) return rest;  // no line parts them
    edge.e[edge.lines] = (dx * frame.s + dy * frame.t) / (len * ray.radius);
    edge.t0[edge.lines] = KernelEdge::shareInverse(rest);
    ++edge.lines;
    return 1.f;
}

}  // namespace

// The probes' turn of a ray: a hash of its bits, the seed and the pass.
static float probeTurn(const PhotonRay& ray, const CoverageSettings& settings) {
    uint32_t bits[6];
    std::memcpy(bits, &ray.origin, 12);
    std::memcpy(bits + 3, &ray.dir, 12);
    uint64_t h = settings.pass;
    for (uint32_t b : bits) h = mix64(h ^ b);
    return toUnitFloat(uint32_t(hashKey(settings.seed, Stage::Coverage, h)));
}

namespace {

// G(t) at 1024 steps of [−1, 1], integrated from the biweight kernel's marginal across a line,
// ∝ (1 − x²)^{5/2}.
constexpr int kShareSteps = 1024;
const std::vector<float>& shareTable() {
    static const std::vector<float> table = [] {
        std::vector<double> g(kShareSteps + 1, 0.0);
        constexpr int kSub = 64;
        for (int i = 0; i < kShareSteps; ++i) {
            double sum = 0.0;
            for (int j = 0; j < kSub; ++j) {
                const double x = -1.0 + 2.0 * (i + (j + 0.5) / kSub) / kShareSteps;
                sum += std::pow(1.0 - x * x, 2.5);
            }
            g[size_t(i) + 1] = g[size_t(i)] + sum;
        }
        std::vector<float> out(g.size());
        for (size_t i = 0; i < g.size(); ++i) out[i] = float(g[i] / g.back());
        return out;
    }();
    return table;
}

// Counts a photon of coverage c in the stats and divides its flux by `share` (at least
// minCoverage); a photon none of whose probes arrived keeps its flux: nothing measured to divide by.
void divideFlux(PhotonRay& ray, float c, float share, const CoverageSettings& settings, CoverageStats& st) {
    ++st.photons;
    st.coverageSum += c;
    if (c < 1.f) ++st.partial;
    if (c > 0.f)
        ray.flux /= std::max(share, settings.minCoverage);
    else
        ++st.uncovered;
}

// Divides the flux by the coverage c, halving the kernel first where c is below kShrinkBelow.
void divideByCoverage(const RayAccel& accel, PhotonRay& ray, const CoverageSettings& settings, CoverageStats& st, float turn,
                      float c) {
    if (c < CoverageSettings::kShrinkBelow) {
        // The same absolute reach past x(i): it is the scene's bounds or h·tan θ at the hit.
        ray.radius *= 0.5f;
        ray.reach *= 2.f;
        c = coverageOf(accel, ray, settings.probes, turn, settings.receiverWindow);
        ++st.shrunk;
    }
    divideFlux(ray, c, c, settings, st);
}

}  // namespace

float KernelEdge::share(float t) {
    const std::vector<float>& g = shareTable();
    const float x = (std::clamp(t, -1.f, 1.f) + 1.f) * (0.5f * kShareSteps);
    const int i = std::min(int(x), kShareSteps - 1);
    return g[size_t(i)] + (x - float(i)) * (g[size_t(i) + 1] - g[size_t(i)]);
}

float KernelEdge::shareInverse(float c) {
    const std::vector<float>& g = shareTable();
    const size_t i = std::clamp<size_t>(size_t(std::lower_bound(g.begin(), g.end(), c) - g.begin()), 1, kShareSteps);
    const float f = g[i] > g[i - 1] ? std::clamp((c - g[i - 1]) / (g[i] - g[i - 1]), 0.f, 1.f) : 0.f;
    return -1.f + 2.f * (float(i - 1) + f) / float(kShareSteps);
}

void normalizeCoverage(const RayAccel& accel, PhotonRay& ray, const CoverageSettings& settings, CoverageStats& st,
                       KernelEdge* edge) {
    const float turn = probeTurn(ray, settings);
    if (!edge || !settings.atSamples) {
        divideByCoverage(accel, ray, settings, st, turn, coverageOf(accel, ray, settings.probes, turn, settings.receiverWindow));
        return;
    }
    ProbeRecord record;
    const float c = coverageOf(accel, ray, settings.probes, turn, settings.receiverWindow, &record);
    const float rest = kernelEdges(accel, ray, record, settings.probes, c, *edge);
    if (rest < 0.f) {
        divideByCoverage(accel, ray, settings, st, turn, c);
        return;
    }
    ++st.atSamples;
    divideFlux(ray, c, rest, settings, st);
}

void normalizeKernelCoverage(const RayAccel& accel, PhotonMap& photons, const CoverageSettings& settings,
                             ThreadPool& pool, Reporter& reporter, CoverageStats* statsOut) {
    constexpr int64_t kChunk = 1024;
    const int64_t n = int64_t(photons.rays.size());
    std::vector<CoverageStats> stats(size_t((n + kChunk - 1) / kChunk));
    photons.edges.assign(settings.atSamples ? size_t(n) : 0, KernelEdge());
    reporter.begin("kernel coverage", n, "photons");
    pool.parallelFor(n, kChunk, [&](int64_t b, int64_t e, int) {
        CoverageStats& st = stats[size_t(b / kChunk)];
        for (int64_t i = b; i < e; ++i)
            normalizeCoverage(accel, photons.rays[size_t(i)], settings, st, settings.atSamples ? &photons.edges[size_t(i)] : nullptr);
        reporter.advance(e - b);
    });
    reporter.end();
    if (statsOut)
        for (const CoverageStats& s : stats) statsOut->add(s);
}

}  // namespace rs
