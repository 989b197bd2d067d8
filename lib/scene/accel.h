// RayAccel: one Embree BVH over the scene's triangles, behind RAII. Embree errors become
// Error(Embree). Rays are in world space; hits come back as SurfacePoints.
#pragma once

#include <memory>

#include "scene/scene.h"
#include "scene/triangle_bvh.h"

namespace rs {

struct SurfacePoint {
    Vec3 p;          // world position
    Vec3 ng;         // geometric normal of the winding (front side), unit
    Vec3 ns;         // shading normal (interpolated, turned by a normal map), unit
    ShadingAttributes attr;  // uvs and vertex colour
    // Width of the ray's footprint across the surface in world units (ray_cone.h), for
    // filtering textures (Scene::uvFootprint, Texture::lodOf); 0, as intersect() leaves it: a
    // point, the full-size image.
    float footprint = 0.f;
    uint32_t tri = 0;
    uint32_t material = 0;
    bool frontFace = true;  // the ray came from the side ng points to
};

class RayAccel {
public:
    RayAccel(const Scene& scene, int threads);
    ~RayAccel();
    RayAccel(const RayAccel&) = delete;
    RayAccel& operator=(const RayAccel&) = delete;

    // Closest hit along o + t·d, t in (0, tmax); d need not be unit.
    bool intersect(const Vec3& o, const Vec3& d, float tmax, SurfacePoint& hit, float& t) const;
    // Anything in (0, tmax)?
    bool occluded(const Vec3& o, const Vec3& d, float tmax) const;
    // Up to kPacket segments from[i] → to at once (one Embree packet, the rays marked coherent:
    // they share an end). Bit i of the result: something lies strictly between from[i] and to.
    static constexpr int kPacket = 16;
    uint32_t occludedToPoint(const Vec3* from, int count, const Vec3& to) const;
    // Closest hits of up to kPacket parallel rays from[i] + t·dir, t in (0, tmax[i]), at once (one
    // Embree packet, marked coherent). Bit i of the result: ray i hit triangle tri[i] at t[i].
    uint32_t intersectParallel(const Vec3* from, int count, const Vec3& dir, const float* tmax, float* t,
                               uint32_t* tri) const;
    const Scene& scene() const { return scene_; }
    // The same triangles in a TriangleBvh, for queries by cylinder; built on first use.
    const TriangleBvh& triangleBvh() const;

    struct Impl;  // Embree handles

private:
    std::unique_ptr<Impl> impl_;
    const Scene& scene_;
};

// How far a point at p is nudged off its surface before a ray leaves it.
inline float rayOriginOffset(const Vec3& p) {
    return 1e-4f * (1.f + std::max(std::abs(p.x), std::max(std::abs(p.y), std::abs(p.z))));
}

// A ray origin nudged off the surface to the side `w` leaves by.
inline Vec3 offsetRayOrigin(const SurfacePoint& sp, const Vec3& w) {
    float eps = rayOriginOffset(sp.p);
    return sp.p + (glm::dot(w, sp.ng) > 0.f ? eps : -eps) * sp.ng;
}

}  // namespace rs
