// TriangleBvh: a bounding volume hierarchy over the scene's triangles for the one query
// Embree does not offer: which triangles lie near a cylinder (a photon segment's kernel
// cylinder, for the splat's visibility shortcut in splat.h). Binary, median splits on the
// longest axis of the triangles' centroids, leaves of up to kLeafSize triangles; 32 bytes a
// node (about one for every two triangles), and a box and an index for every triangle.
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.h"

namespace rs {

struct Scene;

class TriangleBvh {
public:
    explicit TriangleBvh(const Scene& scene);

    // Calls visit(triangle) for every triangle whose bounding box the cylinder o + tω,
    // t ∈ [t0, t1], of radius r touches (the disc boxes of math.h's clipToBox: a superset
    // of the triangles the cylinder meets), in no particular order, until visit returns
    // false; then returns false.
    template <class Visit>
    bool nearCylinder(const Vec3& o, const Vec3& w, float r, float t0, float t1, Visit&& visit) const;

    size_t bytes() const { return nodes_.size() * sizeof(Node) + order_.size() * sizeof(uint32_t); }

    static constexpr uint32_t kLeafSize = 4;

private:
    struct Node {
        Vec3 lo, hi;
        uint32_t first;  // inner: the children are nodes first and first + 1; leaf: into order_
        uint32_t count;  // triangles of a leaf; 0: inner
    };
    void build(const std::vector<Bounds3>& boxes, const std::vector<Vec3>& centres, uint32_t index, uint32_t begin,
               uint32_t end);

    std::vector<Node> nodes_;
    std::vector<uint32_t> order_;  // triangle indices, leaf by leaf
    std::vector<Bounds3> boxes_;   // per triangle, in order_'s order
};

template <class Visit>
bool TriangleBvh::nearCylinder(const Vec3& o, const Vec3& w, float r, float t0, float t1, Visit&& visit) const {
    if (nodes_.empty()) return true;
    float ra[3];
    discHalfExtents(w, r, ra);
    auto touches = [&](const Vec3& lo, const Vec3& hi) {
        float s0 = t0, s1 = t1;
        clipToBox(o, w, ra, lo, hi, s0, s1);
        return s0 <= s1;
    };
    uint32_t stack[64];  // median splits: depth ≤ log2(triangles) + 1
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& n = nodes_[stack[--top]];
        if (!touches(n.lo, n.hi)) continue;
        if (n.count == 0) {
            stack[top++] = n.first + 1;
            stack[top++] = n.first;
            continue;
        }
        for (uint32_t i = n.first; i < n.first + n.count; ++i)
            if (touches(boxes_[i].lo, boxes_[i].hi) && !visit(order_[i])) return false;
    }
    return true;
}

}  // namespace rs
