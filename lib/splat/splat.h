// Splatting in ray space (docs/design.md §8, paper §2 eq. 2 and §5.1): every photon ray traverses
// the occlusion tree as a cylinder of its splat radius h; each visible eye sample y in it
// receives
//     w · f_r(y, −ω, ωo) · Φ · K_h(d⊥) · |n·ω| · V
// where d⊥ is y's distance to the ray's line, K_h the biweight kernel normalised over the
// disc of radius h perpendicular to ω, and V the occlusion mask's visibility at y. Light
// lands in the film layer of the photon's class (direct, indirect, caustic).
#pragma once

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "core/simd.h"
#include "output/film.h"
#include "scene/accel.h"
#include "occlusion/cylinder_index.h"
#include "occlusion/kdtree_traverse.h"
#include "splat/coverage.h"
#include "splat/photons.h"

namespace rs {

class ThreadPool;
struct Stats;
class Reporter;

// Contributions: (photon, eye sample) pairs that received energy. Visibility rays: Embree
// occlusion rays of the receiver rules; visible by planes: rule 2 decided without a ray
// (SegmentReceivers). Refused: samples the receiver rules refused, behind the origin's plane or
// hidden from it. Unseen: photons (with the coverage measured in the splat) whose cylinder held
// no eye sample that faces them, so that neither coverage nor rays were spent on them.
#define RS_SPLAT_COUNTERS(X)                                                                         \
    X(contributions, "splat_contributions") X(visibilityRays, "splat_visibility_rays")                \
    X(visibleByPlanes, "splat_visible_by_planes") X(refusedBehindOrigin, "splat_refused_behind_origin") \
    X(refusedHidden, "splat_refused_hidden") X(unseen, "splat_photons_unseen")
struct SplatStats {
    TraversalStats traversal;
    RS_SPLAT_COUNTERS(RS_COUNTER_MEMBER)
    void add(const SplatStats& o) {
        traversal.add(o.traversal);
        RS_SPLAT_COUNTERS(RS_COUNTER_ADD)
    }
    void report(Stats& stats) const {  // splat_* and traversal_* counts
        traversal.report(stats);
        RS_SPLAT_COUNTERS(RS_COUNTER_REPORT)
    }
};

// The receiver rules of one photon segment x(i−1) → x(i) (world space): whether an eye
// sample y in the segment's cylinder may take its light at all. Both are exact in the
// scene's geometry, so they hold whatever the grid and the radius:
//  1. Origin: y lies in front of the tangent plane of the surface the segment leaves,
//     (y − x(i−1))·n > 0: light leaving a surface does not reach the space behind it.
//  2. Visibility: the straight line from y (lifted off its surface to the side it is seen
//     from) to x(i−1) crosses no surface — equation (2)'s V(y, x(i−1)) itself, one Embree
//     occlusion ray. The mask approximates it by parallel rays along ω, which miss a wall
//     that runs beside the ray, and count only the back-facing side of a wall, whose
//     discrete occlusion sums can fall short of full; this catches both. A sample behind
//     the surface the segment ends on is behind it as seen from x(i−1) too.
// Rule 2 without the ray: every such line lies inside the kernel's cylinder (radius h, from
// x(i−1) to where the kernel ends, widened by the lift), so only the triangles near it
// (TriangleBvh) can cross one. When there are at most kMaxPlanes of them and x(i−1) lies off
// each one's plane, a lifted y sees x(i−1) when, for every such triangle, either
//  • y is on x(i−1)'s side of its plane: a line between two points on one side of a plane does
//    not cross it; or
//  • the point q where the line crosses the plane lies outside the triangle: outside one of
//    the three planes through x(i−1) and an edge (the triangle's cone seen from x(i−1)). With
//    h_x = x(i−1)'s height over the triangle's plane and s_y = y's (≤ 0), q = x(i−1) +
//    h_x/(h_x − s_y)·(y − x(i−1)), so its distance past the edge plane is that fraction of y's.
// Both are decided with a margin m that covers the rounding of the planes' equations (the
// edge planes are made in double precision), q by at least m past the edge plane, so such a y
// is one Embree would find visible too; the others ask Embree. On the glossy box this decides
// about nine in ten of them.
class SegmentReceivers {
public:
    enum Verdict { kReceives = -1, kBehindOrigin = 0, kHidden = 1, kVerdictCount = 2 };
    static constexpr int kMaxPlanes = 16;

    // withPlanes: gather the triangles near the cylinder for surelyVisible (else it says no).
    // windowed: the ray's samples lie within its receiver window (PhotonRay::kernelEnd).
    SegmentReceivers(const RayAccel& accel, const PhotonRay& ray, bool withPlanes, bool windowed = false);
    // Rule 1 for y.
    bool inFrontOfOrigin(const Vec3& y) const {
        return !hasOriginNormal_ || glm::dot(y - origin_, originNormal_) > 0.f;
    }
    // The point rule 2 asks about for a sample at y whose geometric normal, on the side it is
    // seen from, is ng.
    static Vec3 lift(const Vec3& y, const Vec3& ng) { return y + rayOriginOffset(y) * ng; }
    // Rule 2 by the triangles near the cylinder alone: true when the lifted point surely sees
    // x(i−1); false when Embree must say.
    bool surelyVisible(const Vec3& lifted) const {
        if (blockerCount_ < 0) return false;
        const Vec3 rel = lifted - origin_;
        for (int k = 0; k < blockerCount_; ++k) {
            const Blocker& b = blockers_[k];
            const float side = glm::dot(b.n, lifted) - b.d;
            if (side > b.margin) continue;
            const float reach = b.margin * (b.height - side);
            if (!(glm::dot(b.edge[0], rel) * b.height > reach || glm::dot(b.edge[1], rel) * b.height > reach ||
                  glm::dot(b.edge[2], rel) * b.height > reach))
                return false;
        }
        return true;
    }
#if defined(__SSE2__)
    // surelyVisible for four lifted points given by their coordinates' lanes: bit k for point k
    // (the same operations in the same order, lane by lane).
    uint32_t surelyVisible4(__m128 x, __m128 y, __m128 z) const {
        if (blockerCount_ < 0) return 0;
        const __m128 rx = _mm_sub_ps(x, wide_.origin[0]), ry = _mm_sub_ps(y, wide_.origin[1]), rz = _mm_sub_ps(z, wide_.origin[2]);
        __m128 all = _mm_castsi128_ps(_mm_set1_epi32(-1));
        for (int k = 0; k < blockerCount_; ++k) {
            const WideBlocker& b = wide_.blockers[k];
            const __m128 side = _mm_sub_ps(dot4(b.n, x, y, z), b.d);
            __m128 clear = _mm_cmpgt_ps(side, b.margin);
            if (_mm_movemask_ps(_mm_andnot_ps(clear, all)) != 0) {  // some live lane is behind the plane
                const __m128 reach = _mm_mul_ps(b.margin, _mm_sub_ps(b.height, side));
                for (int e = 0; e < 3; ++e)
                    clear = _mm_or_ps(clear, _mm_cmpgt_ps(_mm_mul_ps(dot4(b.edge[e], rx, ry, rz), b.height), reach));
                all = _mm_and_ps(all, clear);
                if (_mm_movemask_ps(all) == 0) return 0;
            }
        }
        return uint32_t(_mm_movemask_ps(all));
    }
#endif
    bool hasOriginNormal() const { return hasOriginNormal_; }
    const Vec3& originNormal() const { return originNormal_; }
    // Rule 2 by Embree for up to RayAccel::kPacket lifted points at once: bit i set when point
    // i is hidden from x(i−1).
    uint32_t hidden(const Vec3* lifted, int count) const;

private:
    struct Blocker {  // a triangle near the cylinder
        Vec3 n;       // its plane's unit normal, turned so that x(i−1) is on its positive side
        float d, margin;
        float height;  // x(i−1)'s height over the plane, > margin
        Vec3 edge[3];  // unit normals of the planes through x(i−1) and an edge, out of the cone
    };
    void findBlockers(const PhotonRay& ray, bool windowed);
#if defined(__SSE2__)
    struct WideBlocker {  // a Blocker's numbers, each in all four lanes
        __m128 n[3], d, margin, height, edge[3][3];
    };
    struct Wide {
        __m128 origin[3];
        WideBlocker blockers[kMaxPlanes];
    };
    void widenBlockers();
#endif

    const RayAccel& accel_;
    Vec3 origin_, originNormal_;
    bool hasOriginNormal_;
    int blockerCount_ = -1;  // -1: the triangles cannot decide
    Blocker blockers_[kMaxPlanes];
#if defined(__SSE2__)
    Wide wide_;  // for surelyVisible4, made with the blockers
#endif
};

// Biweight kernel over the disc of radius h: ∫ K dA = 1.
inline float biweightKernel(float d2, float h2) {
    float x = 1.f - d2 / h2;
    return x <= 0.f ? 0.f : 3.f / (kPi * h2) * x * x;
}

struct SplatSettings {
    // The paper's method: the tree's mask and the receiver rules. Off for splat-novis, ray
    // splatting without visibility (the paper's Fig. 4b), whose tree holds no occluders.
    bool visibility = true;
    // Of the pass's photons (in the splat's coherent order, whole chunks of kChunk), share
    // `share` of `shares` equal parts: a distributed render's ranks split a pass this way
    // (docs/design.md §11). The chunks are the same as in one process, so are the sums.
    int share = 0, shares = 1;
    // Rule 2 decided by planes where they can (SegmentReceivers): the same image as asking
    // Embree every time (off), which the tests compare it with.
    bool visibilityPlanes = true;
    // The samples the mask leaves wholly visible are received four at a time (SSE): the same
    // operations lane by lane, so the same film as one at a time (off), which the tests compare.
    bool batches = true;
    // Only surfaces within PhotonRay::kReceiverWindow radii of x(i) receive (the kernel coverage
    // counts the same): with visibility by rays, not with the paper's mask.
    bool receiverWindow = true;
    // Non-null: each photon's kernel coverage is measured (normalizeCoverage) once its cylinder
    // has reached an eye sample that may receive it, and not for the photons whose kernels land
    // where the camera sees nothing (half of them on the staircase interior).
    const CoverageSettings* coverage = nullptr;
    // Non-null: the samples a cylinder reaches are found through this index over their positions
    // (the sparse receivers: no occluders to walk), not through the tree, whose grid then only
    // orders the photons. The same samples take the same light.
    const CylinderIndex* index = nullptr;
    // The least share of a kernel a sample's light is divided by, with kernel edges (kernel_edge.h).
    float minCoverage = CoverageSettings{}.minCoverage;
    static constexpr int64_t kChunk = 256;
};

// Adds the photons' light to `film` (direct, indirect and caustic layers; pixel = eye
// sample's pixel index). The result does not depend on the thread count: contributions are
// summed as 64-bit fixed-point integers, whose sum does not depend on order.
void splatPhotons(const RayAccel& accel, const OcclusionTree& tree, const EyeSamples& samples,
                  const PhotonMap& photons, const SplatSettings& settings, FixedFilm& film, ThreadPool& pool,
                  Reporter& reporter, SplatStats* stats = nullptr, CoverageStats* coverageStats = nullptr);

}  // namespace rs
