// Ray cones for texture filtering (docs/design.md §3; the ray-cone rule of "Texture Level of
// Detail Strategies for Real-Time Ray Tracing", Akenine-Möller et al.): a ray stands for a cone
// of rays, `width` wide (world units) where it starts and widening by `spread` (radians) per unit
// of length. Where it hits a surface it covers width / |cos θ| there (SurfacePoint::footprint),
// which each texture slot states in its own uv units (Scene::uvFootprint: its uv set, its
// transform's scale) and Texture::lodOf turns into a mip level: texture detail finer
// than what a pixel (or a bounce's lobe) averages is averaged by the mip chain instead of by
// noise between samples.
#pragma once

#include <cmath>

#include "scene/accel.h"
#include "scene/bsdf.h"

namespace rs {

struct RayCone {
    float width = 0.f;
    float spread = 0.f;

    // A ray leaving a rough surface (or a light) stands for its lobe, not a pixel: at least this
    // wide an angle. After a diffuse bounce (and for photons, which the splat spreads over
    // kernels anyway) texture detail finer than about a tenth of the distance is filtered away.
    static constexpr float kRoughSpread = 0.1f;
    // Grazing hits: the footprint across the surface stops growing below this cosine (an
    // isotropic filter over the long axis of the ellipse would blur the short one away).
    static constexpr float kMinCos = 0.1f;

    // Camera rays: the angle one pixel spans at the image's centre (a pinhole), or one pixel's
    // height on the camera's plane and no spread (orthographic).
    static RayCone fromCamera(const Camera& camera, int height) {
        if (camera.projection == Projection::Orthographic) return {2.f * camera.ymag / float(height), 0.f};
        return {0.f, 2.f * std::tan(0.5f * camera.yfov) / float(height)};
    }
    static RayCone fromLight() { return {0.f, kRoughSpread}; }

    float widthAt(float t) const { return width + spread * t; }

    // Sets sp.footprint for the cone's hit at distance t along direction d (unit).
    void footprintAt(SurfacePoint& sp, float t, const Vec3& d) const {
        const float cosine = std::max(std::abs(glm::dot(sp.ng, d)), kMinCos);
        sp.footprint = widthAt(t) / cosine;
    }

    // The cone leaving the hit at distance t once bsdf scattered it: a mirror or glass keeps the
    // spread (flat surfaces: no curvature term); a rough lobe widens it to its own width (GGX α,
    // about the lobe's angle), at most kRoughSpread; a diffuse one to kRoughSpread.
    RayCone scattered(float t, const Bsdf& bsdf) const {
        if (bsdf.isDelta()) return {widthAt(t), spread};
        const float lobe = bsdf.hasGlossyLobe() ? std::min(bsdf.ggxAlpha(), kRoughSpread) : kRoughSpread;
        return {widthAt(t), std::max(spread, lobe)};
    }
};

}  // namespace rs
