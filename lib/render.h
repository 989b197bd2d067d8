// The whole pipeline on one page (DESIGN §1): render() calls the stages in order.
#pragma once

#include "config.h"
#include "film.h"
#include "log.h"
#include "scene.h"
#include "stats.h"

namespace rs {

struct RenderResult {
    Film film;
    Stats stats;
    ImageAttributes attributes;  // config + timings, for the EXR header
};

RenderResult render(const Scene& scene, const RenderConfig& cfg, Reporter& reporter);

// EXR (+ PNG, + stats JSON) as the config asks, each written atomically.
void writeOutputs(const RenderResult& result, const RenderConfig& cfg);

// The version string of this build.
const char* versionString();

}  // namespace rs
