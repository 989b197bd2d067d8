// RenderConfig: every setting of a render in one aggregate with defaults; the CLI fills it,
// validate() refuses absurd values with a one-line Error(Config), and every stage takes it
// as const&. Every setting that changes the image is written to the EXR header.
#pragma once

#include <string>

#include "film.h"

namespace rs {

enum class Method { Path };
const char* methodName(Method m);
Method parseMethod(const std::string& name);  // throws Error(Config)

struct RenderConfig {
    std::string scene;
    std::string output;     // .exr
    std::string png;        // optional preview
    std::string statsJson;  // optional
    std::string camera;     // name; empty = first in the file

    Method method = Method::Path;
    int width = 500;   // 0: from height and the camera's aspect
    int height = 0;    // 0: from width and the camera's aspect
    int spp = 16;      // samples per pixel (per pass with --time-limit)
    int maxDepth = 32;
    uint64_t seed = 0;
    int threads = 0;         // 0: all hardware threads
    double timeLimit = 0.0;  // seconds; > 0: render passes until the time is up
    float exposure = 0.f;    // PNG preview, stops

    void validate() const;
    // Width and height for a camera of aspect `aspect` (0: unknown, taken as 1).
    void resolution(float aspect, int& w, int& h) const;
    ImageAttributes attributes() const;  // for the EXR header
};

}  // namespace rs
