// CylinderIndex (cylinder_index.h): points in Morton order, sixteen to a box, boxes of boxes.
#include "occlusion/cylinder_index.h"

#include <algorithm>
#include <cmath>
#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace rs {

constexpr float kFar = 1e30f;  // the padding's coordinates: no cylinder reaches them

// What a query tests against, relative to the axis' origin: a point at u = p − origin lies
// at depth t = u·ω and distance |u × ω| from the axis. Made once a query, its numbers each in
// four lanes where SSE is there.
struct CylinderIndexQuery {
    Vec3 origin, dir, inv;  // inv: 1/ω, a component of ω below 1e-20 taken as 1e-20
    float begin, end;  // depths, widened by the slack
    float radius;      // widened by the slack
#if defined(__SSE2__)
    __m128 ox, oy, oz, dx, dy, dz, ix, iy, iz, begin4, end4, radius4, r2;
    CylinderIndexQuery(const Vec3& o, const Vec3& d, const Vec3& i, float b, float e, float r)
        : origin(o), dir(d), inv(i), begin(b), end(e), radius(r), ox(_mm_set1_ps(o.x)), oy(_mm_set1_ps(o.y)),
          oz(_mm_set1_ps(o.z)), dx(_mm_set1_ps(d.x)), dy(_mm_set1_ps(d.y)), dz(_mm_set1_ps(d.z)), ix(_mm_set1_ps(i.x)),
          iy(_mm_set1_ps(i.y)), iz(_mm_set1_ps(i.z)), begin4(_mm_set1_ps(b)), end4(_mm_set1_ps(e)), radius4(_mm_set1_ps(r)),
          r2(_mm_set1_ps(r * r)) {}
    // |u × ω|²: the squared distance from the axis.
    __m128 across2(__m128 ux, __m128 uy, __m128 uz) const {
        const __m128 cx = _mm_sub_ps(_mm_mul_ps(uy, dz), _mm_mul_ps(uz, dy));
        const __m128 cy = _mm_sub_ps(_mm_mul_ps(uz, dx), _mm_mul_ps(ux, dz));
        const __m128 cz = _mm_sub_ps(_mm_mul_ps(ux, dy), _mm_mul_ps(uy, dx));
        return _mm_add_ps(_mm_add_ps(_mm_mul_ps(cx, cx), _mm_mul_ps(cy, cy)), _mm_mul_ps(cz, cz));
    }
#else
    CylinderIndexQuery(const Vec3& o, const Vec3& d, const Vec3& i, float b, float e, float r)
        : origin(o), dir(d), inv(i), begin(b), end(e), radius(r) {}
#endif
};

CylinderIndex::CylinderIndex(const std::vector<Vec3>& points) {
    if (points.empty()) return;
    Vec3 lo(INFINITY), hi(-INFINITY);
    for (const Vec3& p : points)
        if (isFinite(p)) lo = glm::min(lo, p), hi = glm::max(hi, p);
    const Vec3 scale = 1023.f / glm::max(hi - lo, Vec3(1e-20f));
    std::vector<uint64_t> keyed(points.size());  // (Morton code, index): ties by index; not finite: last
    for (size_t i = 0; i < points.size(); ++i) {
        uint32_t code = UINT32_MAX;
        if (isFinite(points[i])) {
            const Vec3 q = glm::clamp((points[i] - lo) * scale, Vec3(0.f), Vec3(1023.f));
            code = spreadBits(uint32_t(q.x)) | spreadBits(uint32_t(q.y)) << 1 | spreadBits(uint32_t(q.z)) << 2;
        }
        keyed[i] = uint64_t(code) << 32 | i;
    }
    std::sort(keyed.begin(), keyed.end());

    // The leaves: the points in that order, the last leaf padded with points no cylinder reaches.
    const size_t leaves = (points.size() + kFan - 1) / kFan, padded = leaves * kFan;
    x_.assign(padded, kFar), y_.assign(padded, kFar), z_.assign(padded, kFar), id_.assign(padded, 0);
    size_t finite = 0;
    for (size_t k = 0; k < points.size(); ++k) {
        const uint32_t i = uint32_t(keyed[k]);
        if (!isFinite(points[i])) break;
        x_[k] = points[i].x, y_[k] = points[i].y, z_[k] = points[i].z, id_[k] = i;
        finite = k + 1;
    }

    // Boxes: the leaves', then sixteen of a level to one of the next, up to a level of ≤ kFan.
    std::vector<Vec3> boxLo(leaves, Vec3(kFar)), boxHi(leaves, Vec3(kFar));
    for (size_t k = 0; k < finite; ++k) {
        if (k % kFan == 0) boxLo[k / kFan] = Vec3(INFINITY), boxHi[k / kFan] = Vec3(-INFINITY);
        const Vec3 p(x_[k], y_[k], z_[k]);
        boxLo[k / kFan] = glm::min(boxLo[k / kFan], p), boxHi[k / kFan] = glm::max(boxHi[k / kFan], p);
    }
    for (;;) {
        Boxes level;
        const size_t n = boxLo.size(), whole = (n + kFan - 1) / kFan * kFan;
        for (size_t b = 0; b < whole; ++b) {
            const bool real = b < n;
            const Vec3 c = real ? 0.5f * (boxLo[b] + boxHi[b]) : Vec3(kFar);
            const Vec3 e = real ? 0.5f * (boxHi[b] - boxLo[b]) : Vec3(0.f);
            level.cx.push_back(c.x), level.cy.push_back(c.y), level.cz.push_back(c.z);
            level.ex.push_back(e.x), level.ey.push_back(e.y), level.ez.push_back(e.z);
            level.r.push_back(glm::length(e));
        }
        levels_.push_back(std::move(level));
        if (n <= size_t(kFan)) break;
        const size_t above = whole / kFan;
        std::vector<Vec3> lo2(above, Vec3(INFINITY)), hi2(above, Vec3(-INFINITY));
        for (size_t b = 0; b < n; ++b)
            lo2[b / kFan] = glm::min(lo2[b / kFan], boxLo[b]), hi2[b / kFan] = glm::max(hi2[b / kFan], boxHi[b]);
        boxLo.swap(lo2), boxHi.swap(hi2);
    }
}

void CylinderIndex::query(const Vec3& origin, const Vec3& dir, float radius, float begin, float end,
                          std::vector<uint32_t>& out, Counts& counts) const {
    if (levels_.empty() || !(end > begin)) return;
    const float slack = 0.01f * radius;
    Vec3 inv;
    for (int a = 0; a < 3; ++a) inv[a] = 1.f / (std::abs(dir[a]) > 1e-20f ? dir[a] : std::copysign(1e-20f, dir[a]));
    const CylinderIndexQuery q(origin, dir, inv, begin - slack, end + slack, radius + slack);
    visit(q, int(levels_.size()) - 1, 0, out, counts);
}

// Bit k: box first + k of `boxes` may meet the cylinder. The axis' depths inside the box widened
// by the radius on every side (which holds every point of the cylinder near the box), by slabs,
// must meet (begin, end], and the box's bounding sphere must lie within the radius of the axis.
uint32_t CylinderIndex::openBoxes(const Boxes& boxes, size_t first, const CylinderIndexQuery& q) {
    uint32_t open = 0;
#if defined(__SSE2__)
    for (int g = 0; g < kFan; g += 4) {
        const size_t b = first + size_t(g);
        const __m128 ux = _mm_sub_ps(_mm_loadu_ps(&boxes.cx[b]), q.ox), uy = _mm_sub_ps(_mm_loadu_ps(&boxes.cy[b]), q.oy),
                     uz = _mm_sub_ps(_mm_loadu_ps(&boxes.cz[b]), q.oz);
        const __m128 wx = _mm_add_ps(_mm_loadu_ps(&boxes.ex[b]), q.radius4), wy = _mm_add_ps(_mm_loadu_ps(&boxes.ey[b]), q.radius4),
                     wz = _mm_add_ps(_mm_loadu_ps(&boxes.ez[b]), q.radius4);
        const __m128 x0 = _mm_mul_ps(_mm_sub_ps(ux, wx), q.ix), x1 = _mm_mul_ps(_mm_add_ps(ux, wx), q.ix);
        const __m128 y0 = _mm_mul_ps(_mm_sub_ps(uy, wy), q.iy), y1 = _mm_mul_ps(_mm_add_ps(uy, wy), q.iy);
        const __m128 z0 = _mm_mul_ps(_mm_sub_ps(uz, wz), q.iz), z1 = _mm_mul_ps(_mm_add_ps(uz, wz), q.iz);
        const __m128 near = _mm_max_ps(_mm_max_ps(_mm_min_ps(x0, x1), _mm_min_ps(y0, y1)), _mm_max_ps(_mm_min_ps(z0, z1), q.begin4));
        const __m128 far = _mm_min_ps(_mm_min_ps(_mm_max_ps(x0, x1), _mm_max_ps(y0, y1)), _mm_min_ps(_mm_max_ps(z0, z1), q.end4));
        const __m128 reach = _mm_add_ps(q.radius4, _mm_loadu_ps(&boxes.r[b]));
        const __m128 in = _mm_and_ps(_mm_cmple_ps(near, far), _mm_cmple_ps(q.across2(ux, uy, uz), _mm_mul_ps(reach, reach)));
        open |= uint32_t(_mm_movemask_ps(in)) << g;
    }
#else
    for (int k = 0; k < kFan; ++k) {
        const size_t b = first + size_t(k);
        const Vec3 u = Vec3(boxes.cx[b], boxes.cy[b], boxes.cz[b]) - q.origin;
        const Vec3 w = Vec3(boxes.ex[b], boxes.ey[b], boxes.ez[b]) + q.radius;
        const Vec3 t0 = (u - w) * q.inv, t1 = (u + w) * q.inv;
        const Vec3 lo = glm::min(t0, t1), hi = glm::max(t0, t1);
        const float near = std::max(std::max(lo.x, lo.y), std::max(lo.z, q.begin));
        const float far = std::min(std::min(hi.x, hi.y), std::min(hi.z, q.end));
        const Vec3 c = glm::cross(u, q.dir);
        const float reach = q.radius + boxes.r[b];
        if (near <= far && glm::dot(c, c) <= reach * reach) open |= 1u << k;
    }
#endif
    return open;
}

// Bit j: point first + j lies within the (widened) cylinder.
uint32_t CylinderIndex::pointsInside(size_t first, const CylinderIndexQuery& q) const {
    uint32_t in = 0;
#if defined(__SSE2__)
    for (int g = 0; g < kFan; g += 4) {
        const size_t p = first + size_t(g);
        const __m128 ux = _mm_sub_ps(_mm_loadu_ps(&x_[p]), q.ox), uy = _mm_sub_ps(_mm_loadu_ps(&y_[p]), q.oy),
                     uz = _mm_sub_ps(_mm_loadu_ps(&z_[p]), q.oz);
        const __m128 t = _mm_add_ps(_mm_add_ps(_mm_mul_ps(ux, q.dx), _mm_mul_ps(uy, q.dy)), _mm_mul_ps(uz, q.dz));
        const __m128 m = _mm_and_ps(_mm_and_ps(_mm_cmpgt_ps(t, q.begin4), _mm_cmple_ps(t, q.end4)),
                                    _mm_cmple_ps(q.across2(ux, uy, uz), q.r2));
        in |= uint32_t(_mm_movemask_ps(m)) << g;
    }
#else
    for (int j = 0; j < kFan; ++j) {
        const size_t p = first + size_t(j);
        const Vec3 u = Vec3(x_[p], y_[p], z_[p]) - q.origin;
        const float t = glm::dot(u, q.dir);
        const Vec3 c = glm::cross(u, q.dir);
        if (t > q.begin && t <= q.end && glm::dot(c, c) <= q.radius * q.radius) in |= 1u << j;
    }
#endif
    return in;
}

// Boxes [first, first + kFan) of `level`: each that may meet the cylinder is opened, a leaf's
// points tested.
void CylinderIndex::visit(const CylinderIndexQuery& q, int level, size_t first, std::vector<uint32_t>& out,
                          Counts& counts) const {
    counts.boxes += kFan;
    for (uint32_t open = openBoxes(levels_[size_t(level)], first, q); open; open &= open - 1) {
        const size_t b = first + size_t(__builtin_ctz(open));
        if (level > 0) {
            visit(q, level - 1, b * kFan, out, counts);
            continue;
        }
        counts.points += kFan;
        for (uint32_t in = pointsInside(b * kFan, q); in; in &= in - 1) out.push_back(id_[b * kFan + size_t(__builtin_ctz(in))]);
    }
}

}  // namespace rs
