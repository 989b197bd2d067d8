#include "grid/occlusion_grid.h"

#include <cmath>

#include "core/error.h"

namespace rs {

GridGeometry gridForBounds(const Bounds3& bounds, int resolution) {
    if (resolution < 1 || resolution > kMaxGridResolution)
        throw Error(ErrorKind::Config, "grid resolution " + std::to_string(resolution) + " is out of range (1.." +
                                           std::to_string(kMaxGridResolution) + ")");
    if (bounds.empty()) throw Error(ErrorKind::Scene, "cannot voxelize an empty scene");
    GridGeometry g;
    Vec3 extent = bounds.extent();
    float longest = std::max(maxComponent(extent), 1e-6f);
    g.voxelSize = longest / float(resolution);
    for (int a = 0; a < 3; ++a) g.dims[a] = std::max(1, int(std::ceil(extent[a] / g.voxelSize - 1e-4f))) + 2;
    // Centre the bounds in the padded grid.
    Vec3 span = Vec3(g.dims) * g.voxelSize;
    g.origin = bounds.center() - 0.5f * span;
    return g;
}

size_t OcclusionGrid::occupiedCount() const {
    size_t n = 0;
    for (size_t i = 0; i < geometry.voxelCount(); ++i) n += occupied(i);
    return n;
}

}  // namespace rs
