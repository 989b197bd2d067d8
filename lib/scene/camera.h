// Camera rays: raster (x right, y down, pixel centres at +0.5) → world-space ray. A pinhole
// (every ray from the camera's position) or orthographic (parallel rays along `forward`, each
// from its own point of the plane through the camera's position); scene.h's Camera.
#pragma once

#include "scene/scene.h"

namespace rs {

class CameraRays {
public:
    CameraRays(const Camera& cam, int width, int height)
        : cam_(cam), width_(width), height_(height),
          halfHeight_(cam.projection == Projection::Orthographic ? cam.ymag : std::tan(0.5f * cam.yfov)),
          aspect_(float(width) / float(height)) {}

    Vec3 origin(Vec2 raster) const {
        if (cam_.projection == Projection::Perspective) return cam_.position;
        const Vec2 s = screen(raster);
        return cam_.position + s.x * cam_.right + s.y * cam_.up;
    }
    Vec3 direction(Vec2 raster) const {  // unit
        if (cam_.projection == Projection::Orthographic) return cam_.forward;
        const Vec2 s = screen(raster);
        return glm::normalize(cam_.forward + s.x * cam_.right + s.y * cam_.up);
    }

private:
    // The raster point on the screen window: at unit distance for a pinhole, in metres on the
    // camera's plane for an orthographic camera.
    Vec2 screen(Vec2 raster) const {
        return Vec2((2.f * raster.x / width_ - 1.f) * halfHeight_ * aspect_, (1.f - 2.f * raster.y / height_) * halfHeight_);
    }

    Camera cam_;
    int width_, height_;
    float halfHeight_, aspect_;
};

}  // namespace rs
