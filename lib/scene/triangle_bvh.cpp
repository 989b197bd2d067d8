#include "scene/triangle_bvh.h"

#include <algorithm>

#include "scene/scene.h"

namespace rs {

TriangleBvh::TriangleBvh(const Scene& scene) {
    const size_t n = scene.triangleCount();
    if (n == 0) return;
    std::vector<Bounds3> boxes(n);
    std::vector<Vec3> centres(n);
    order_.resize(n);
    for (size_t t = 0; t < n; ++t) {
        for (int k = 0; k < 3; ++k) boxes[t].extend(scene.positions[3 * t + size_t(k)]);
        centres[t] = boxes[t].center();
        order_[t] = uint32_t(t);
    }
    nodes_.reserve(2 * (n / kLeafSize + 1));
    nodes_.emplace_back();
    build(boxes, centres, 0, 0, uint32_t(n));
    boxes_.resize(n);
    for (size_t i = 0; i < n; ++i) boxes_[i] = boxes[order_[i]];
}

// Fills node `index` for order_[begin, end): a leaf, or two children made next to each other.
void TriangleBvh::build(const std::vector<Bounds3>& boxes, const std::vector<Vec3>& centres, uint32_t index,
                        uint32_t begin, uint32_t end) {
    Bounds3 box, centreBox;
    for (uint32_t i = begin; i < end; ++i) box.extend(boxes[order_[i]]), centreBox.extend(centres[order_[i]]);
    nodes_[index].lo = box.lo, nodes_[index].hi = box.hi;
    const Vec3 extent = centreBox.extent();
    if (end - begin <= kLeafSize || maxComponent(extent) <= 0.f) {
        nodes_[index].first = begin, nodes_[index].count = end - begin;
        return;
    }
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
    const uint32_t mid = begin + (end - begin) / 2;
    // Ties broken by the triangle's index: the same tree on every machine.
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end, [&](uint32_t a, uint32_t b) {
        return centres[a][axis] < centres[b][axis] || (centres[a][axis] == centres[b][axis] && a < b);
    });
    const uint32_t children = uint32_t(nodes_.size());
    nodes_.emplace_back(), nodes_.emplace_back();
    nodes_[index].first = children, nodes_[index].count = 0;
    build(boxes, centres, children, begin, mid);
    build(boxes, centres, children + 1, mid, end);
}

}  // namespace rs
