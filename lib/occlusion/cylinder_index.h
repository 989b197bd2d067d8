// CylinderIndex: points in boxes of sixteen, for finding those a photon's cylinder may reach
// (docs/design.md §8, sparse receivers).
//
// Takes:   points in world space (the receivers' positions), kept by index.
// Returns: for a cylinder (an axis o + t·ω, t in (begin, end], radius h), the indices of every
//          point inside it and of a few near it (a superset: the caller tests each point as it
//          would have anyway). Nothing is reordered.
// Space:   world.
//
// The occlusion tree (kdtree.h) walks a cylinder slice by slice for the paper's mask. With
// visibility by rays and no occluders in the tree, the receivers need only a range search, which
// the walk made cost a photon about as much as its coverage probes. Here the points are taken in
// Morton order, sixteen to a leaf box; sixteen boxes make a box of the level above, up to one
// level of at most sixteen. A box is opened where the axis, within (begin, end], meets the box
// widened by the radius on every side (by slabs) and the box's bounding sphere lies within the
// radius of the axis; a leaf's points are tested four at a time, with a slack of a hundredth of
// the radius so that rounding never drops a point the caller keeps. Points that are not finite
// are never found.
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.h"

namespace rs {

struct CylinderIndexQuery;

class CylinderIndex {
public:
    static constexpr int kFan = 16;  // points a leaf, boxes a box

    CylinderIndex() = default;
    explicit CylinderIndex(const std::vector<Vec3>& points);

    // What queries tested, added up: boxes, and points in the leaves opened.
    struct Counts {
        uint64_t boxes = 0, points = 0;
    };

    // Appends to `out` the points that may lie within `radius` of the axis origin + t·dir, t in
    // (begin, end] (dir unit): every one that does, in leaf order.
    void query(const Vec3& origin, const Vec3& dir, float radius, float begin, float end, std::vector<uint32_t>& out,
               Counts& counts) const;

private:
    // A level's boxes: centre, half extent, bounding sphere's radius; padded to a whole kFan
    // with boxes no cylinder reaches.
    struct Boxes {
        std::vector<float> cx, cy, cz, ex, ey, ez, r;
        size_t size() const { return cx.size(); }
    };
    static uint32_t openBoxes(const Boxes& boxes, size_t first, const CylinderIndexQuery& q);
    uint32_t pointsInside(size_t first, const CylinderIndexQuery& q) const;
    void visit(const CylinderIndexQuery& q, int level, size_t first, std::vector<uint32_t>& out, Counts& counts) const;

    std::vector<float> x_, y_, z_;  // the points in leaf order, padded to whole leaves far away
    std::vector<uint32_t> id_;      // their indices
    std::vector<Boxes> levels_;     // levels_[0]: the leaves' boxes; the last: one kFan
};

}  // namespace rs
