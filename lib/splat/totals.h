// Figures summed over a render's splat passes (splat_pass.h), the kernel-scale probe's splats
// included (kernel_probe.h).
#pragma once

#include <cstdint>

#include "splat/coverage.h"
#include "splat/splat.h"

namespace rs {

// The last pass's sizes are reported as they come.
struct SplatTotals {
    SplatStats splat;
    CoverageStats coverage;
    int64_t photonsStored = 0;
    double photonMb = 0.0;
};

}  // namespace rs
