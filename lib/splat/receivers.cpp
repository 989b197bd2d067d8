// The receiver rules' blockers along one photon ray (splat.h's SegmentReceivers): the
// triangles near its cylinder as planes, and the rays for what the planes cannot decide.
#include "splat/splat.h"

#include <algorithm>
#include <cmath>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "scene/accel.h"
#include "scene/scene.h"

namespace rs {

SegmentReceivers::SegmentReceivers(const RayAccel& accel, const PhotonRay& ray, bool withPlanes, bool windowed)
    : accel_(accel), origin_(ray.origin),
      originNormal_(ray.originNormal ? decodeUnit(ray.originNormal) : Vec3(0.f)), hasOriginNormal_(ray.originNormal != 0) {
    if (withPlanes) findBlockers(ray, windowed);
}

// The triangles near the cylinder: their planes oriented to x(i−1), and the planes through
// x(i−1) and each edge. The cylinder is widened by twice the largest lift of a sample in it; a
// side counts only past a margin of 1e-5 × (1 + the largest coordinate involved), far above
// the rounding of the planes' equations (~1e-7 of it) and a tenth of the lift, which puts a
// sample on its surface's front. An edge plane is made in double precision; one whose edge
// points at x(i−1) (no plane) is never passed, so its triangle then blocks whatever is behind
// its plane.
void SegmentReceivers::findBlockers(const PhotonRay& ray, bool windowed) {
    const float o = std::max(std::abs(origin_.x), std::max(std::abs(origin_.y), std::abs(origin_.z)));
    const float length = ray.kernelEnd(windowed);
    const float reach = o + length + ray.radius;
    const float widen = 2.f * rayOriginOffset(Vec3(reach));
    const Scene& scene = accel_.scene();
    const glm::dvec3 x(origin_);
    int count = 0;
    const bool few = accel_.triangleBvh().nearCylinder(
        origin_, ray.dir, ray.radius + widen, -widen, length + widen, [&](uint32_t tri) {
            if (count == kMaxPlanes) return false;
            const Vec3* p = &scene.positions[3 * size_t(tri)];
            const Vec3 c = glm::cross(p[1] - p[0], p[2] - p[0]);
            const float area2 = glm::length(c);
            if (!(area2 > 0.f) || !std::isfinite(area2)) return false;  // no plane to decide by
            Blocker& b = blockers_[count];
            b.n = c / area2;
            b.d = glm::dot(b.n, p[0]);
            float extent = reach;
            for (int k = 0; k < 3; ++k) extent = std::max(extent, maxComponent(glm::abs(p[k])));
            b.margin = 1e-5f * (1.f + extent);
            const float side = glm::dot(b.n, origin_) - b.d;
            if (!(std::abs(side) > b.margin)) return false;  // x(i−1) too close to call
            if (side < 0.f) b.n = -b.n, b.d = -b.d;
            b.height = std::abs(side);
            for (int k = 0; k < 3; ++k) {
                const glm::dvec3 a = glm::dvec3(p[k]) - x, e = glm::dvec3(p[(k + 1) % 3]) - x;
                const glm::dvec3 inside = glm::dvec3(p[(k + 2) % 3]) - x;
                glm::dvec3 n = glm::cross(a, e);
                const double len = glm::length(n);
                if (!(len > 1e-6 * glm::length(a) * glm::length(e))) {
                    b.edge[k] = Vec3(0.f);  // dot 0: never past the margin
                    continue;
                }
                n /= len;
                b.edge[k] = Vec3(glm::dot(n, inside) > 0.0 ? -n : n);
            }
            ++count;
            return true;
        });
    blockerCount_ = few ? count : -1;
#if defined(__SSE2__)
    widenBlockers();
#endif
}

#if defined(__SSE2__)
// The blockers' numbers broadcast once a photon, not once every four samples.
void SegmentReceivers::widenBlockers() {
    for (int a = 0; a < 3; ++a) wide_.origin[a] = _mm_set1_ps(origin_[a]);
    for (int k = 0; k < blockerCount_; ++k) {
        const Blocker& b = blockers_[k];
        WideBlocker& w = wide_.blockers[k];
        for (int a = 0; a < 3; ++a) {
            w.n[a] = _mm_set1_ps(b.n[a]);
            for (int e = 0; e < 3; ++e) w.edge[e][a] = _mm_set1_ps(b.edge[e][a]);
        }
        w.d = _mm_set1_ps(b.d), w.margin = _mm_set1_ps(b.margin), w.height = _mm_set1_ps(b.height);
    }
}
#endif

uint32_t SegmentReceivers::hidden(const Vec3* lifted, int count) const {
    return accel_.occludedToPoint(lifted, count, origin_);
}
}  // namespace rs
