// Kernel coverage (docs/design.md §8): Embree probes along each photon's kernel disc, a packet a
// photon, in parallel over the photons; each photon's numbers depend only on (seed, pass, index).
#include "splat/coverage.h"

#include <algorithm>
#include <cmath>
#include <cstring>

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

// The share of one photon ray's kernel that lands on a receiving surface. Probe k follows the
// disc ray at radius h·√s_k, where s_k = 1 − (1 − (k + ½)/n)^⅓ inverts the biweight kernel's
// radial distribution (its mass inside s = d²/h² is 1 − (1 − s)³), so each probe carries an
// equal share of the kernel's weight; successive probes turn by the golden angle. A probe starts
// where its ray crosses the tangent plane of the surface the photon leaves (rule 1), or at the
// origin's depth, and ends with the cylinder. Like the splat, which takes every sample in the
// cylinder and not only the first along each line, it counts every non-specular surface it
// crosses whose point, lifted to the side the probe comes from, sees x(i−1) (rule 2), and,
// `windowed`, lies within the ray's receiver window (PhotonRay::kernelBegin and kernelEnd), as
// the splat's samples must. The probes of a photon are parallel and their rule-2 rays share an
// end: one packet each.
float coverageOf(const RayAccel& accel, const PhotonRay& ray, int probes, float turn, bool windowed) {
    const Frame frame(ray.dir);
    const Vec3 n = ray.originNormal ? decodeUnit(ray.originNormal) : Vec3(0.f);
    const float cosOrigin = glm::dot(n, ray.dir);
    const float begin = ray.kernelBegin(windowed), end = ray.kernelEnd(windowed);
    const float offset = 2.f * rayOriginOffset(ray.origin);
    const Scene& scene = accel.scene();
    Vec3 from[RayAccel::kPacket], lifted[RayAccel::kPacket];
    float left[RayAccel::kPacket], t[RayAccel::kPacket], depth[RayAccel::kPacket];
    uint32_t tri[RayAccel::kPacket];
    int live = 0;
    for (int k = 0; k < probes; ++k) {
        const float s = 1.f - std::cbrt(1.f - (float(k) + 0.5f) / float(probes));
        const float phi = 2.f * kPi * (turn + float(k) * kGoldenTurn);
        const Vec3 u = ray.radius * std::sqrt(s) * (std::cos(phi) * frame.s + std::sin(phi) * frame.t);
        float start = cosOrigin > 1e-3f ? std::max(0.f, -glm::dot(u, n) / cosOrigin) : 0.f;
        start += offset / std::max(cosOrigin, 0.05f);
        start = std::max(start, begin);  // what lies before the window counts for nothing
        if (!(start < end)) continue;
        from[live] = ray.origin + u + start * ray.dir;
        depth[live] = start;
        left[live++] = end - start;
    }
    int covered = 0;
    for (int crossing = 0; crossing < kMaxCrossings && live > 0; ++crossing) {
        const uint32_t hits = accel.intersectParallel(from, live, ray.dir, left, t, tri);
        int next = 0, receivers = 0;
        for (int i = 0; i < live; ++i) {
            if (!(hits >> i & 1u)) continue;
            const Vec3 p = from[i] + t[i] * ray.dir;
            const Vec3 ng = scene.geometricNormal(tri[i]);
            const float eps = rayOriginOffset(p);
            const Vec3 toward = glm::dot(ray.dir, ng) < 0.f ? ng : -ng;  // the side the probe comes from
            const float at = depth[i] + t[i];
            if (at > begin && !scene.materials[scene.triMaterial[tri[i]]].isSpecular()) lifted[receivers++] = p + eps * toward;
            if (left[i] - t[i] > 0.f) from[next] = p - eps * toward, depth[next] = at, left[next++] = left[i] - t[i];
        }
        if (receivers > 0) covered += receivers - __builtin_popcount(accel.occludedToPoint(lifted, receivers, ray.origin));
        live = next;
    }
    return float(covered) / float(probes);
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

void normalizeCoverage(const RayAccel& accel, PhotonRay& ray, const CoverageSettings& settings, CoverageStats& st) {
    const float turn = probeTurn(ray, settings);
    float c = coverageOf(accel, ray, settings.probes, turn, settings.receiverWindow);
    if (c < CoverageSettings::kShrinkBelow) {
        // The same absolute reach past x(i): it is the scene's bounds or h·tan θ at the hit.
        ray.radius *= 0.5f;
        ray.reach *= 2.f;
        c = coverageOf(accel, ray, settings.probes, turn, settings.receiverWindow);
        ++st.shrunk;
    }
    ++st.photons;
    st.coverageSum += c;
    if (c < 1.f) ++st.partial;
    if (c > 0.f)
        ray.flux /= std::max(c, settings.minCoverage);
    else
        ++st.uncovered;
}

void normalizeKernelCoverage(const RayAccel& accel, PhotonMap& photons, const CoverageSettings& settings,
                             ThreadPool& pool, Reporter& reporter, CoverageStats* statsOut) {
    constexpr int64_t kChunk = 1024;
    const int64_t n = int64_t(photons.rays.size());
    std::vector<CoverageStats> stats(size_t((n + kChunk - 1) / kChunk));
    reporter.begin("kernel coverage", n, "photons");
    pool.parallelFor(n, kChunk, [&](int64_t b, int64_t e, int) {
        CoverageStats& st = stats[size_t(b / kChunk)];
        for (int64_t i = b; i < e; ++i) normalizeCoverage(accel, photons.rays[size_t(i)], settings, st);
        reporter.advance(e - b);
    });
    reporter.end();
    if (statsOut)
        for (const CoverageStats& s : stats) statsOut->add(s);
}

}  // namespace rs
