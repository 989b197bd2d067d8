// Pinhole camera rays: raster (x right, y down, pixel centres at +0.5) → world-space ray.
#pragma once

#include "scene/scene.h"

namespace rs {

class CameraRays {
public:
    CameraRays(const Camera& cam, int width, int height)
        : cam_(cam), width_(width), height_(height), tanHalf_(std::tan(0.5f * cam.yfov)),
          aspect_(float(width) / float(height)) {}

    Vec3 origin() const { return cam_.position; }
    Vec3 direction(Vec2 raster) const {  // unit
        float sx = (2.f * raster.x / width_ - 1.f) * tanHalf_ * aspect_;
        float sy = (1.f - 2.f * raster.y / height_) * tanHalf_;
        return glm::normalize(cam_.forward + sx * cam_.right + sy * cam_.up);
    }

private:
    Camera cam_;
    int width_, height_;
    float tanHalf_, aspect_;
};

}  // namespace rs
