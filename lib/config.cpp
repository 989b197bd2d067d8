#include "config.h"

#include <cmath>

#include "error.h"

namespace rs {

const char* methodName(Method m) {
    switch (m) {
        case Method::Path: return "path";
    }
    return "?";
}

Method parseMethod(const std::string& name) {
    if (name == "path") return Method::Path;
    if (name == "splat" || name == "splat-novis")
        throw Error(ErrorKind::Config, "--method " + name + ": not built yet (available: path)");
    throw Error(ErrorKind::Config, "--method " + name + ": unknown method (available: path)");
}

static void requireRange(const char* flag, double v, double lo, double hi) {
    if (!(v >= lo && v <= hi)) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "%s %g is out of range (%g..%g)", flag, v, lo, hi);
        throw Error(ErrorKind::Config, buf);
    }
}

void RenderConfig::validate() const {
    requireRange("--width", width, 0, 16384);
    requireRange("--height", height, 0, 16384);
    if (width == 0 && height == 0) throw Error(ErrorKind::Config, "--width and --height cannot both be 0");
    requireRange("--spp", spp, 1, 1 << 20);
    requireRange("--max-depth", maxDepth, 1, 1024);
    requireRange("--threads", threads, 0, 1024);
    requireRange("--time-limit", timeLimit, 0, 1e7);
    requireRange("--exposure", exposure, -50, 50);
    if (output.empty()) throw Error(ErrorKind::Config, "no output file: give -o FILE.exr");
    double pixels = double(width ? width : height) * double(height ? height : width);
    if (pixels * spp > 1e12) throw Error(ErrorKind::Config, "--width × --height × --spp is absurdly large");
}

void RenderConfig::resolution(float aspect, int& w, int& h) const {
    if (!(aspect > 0.f) || !std::isfinite(aspect)) aspect = 1.f;
    w = width;
    h = height;
    if (w == 0) w = std::max(1, int(std::lround(h * aspect)));
    if (h == 0) h = std::max(1, int(std::lround(w / aspect)));
    if (w > 16384 || h > 16384)
        throw Error(ErrorKind::Config, "resolution " + std::to_string(w) + "x" + std::to_string(h) + " from the camera's aspect is too large");
}

ImageAttributes RenderConfig::attributes() const {
    return {{"method", methodName(method)},
            {"spp", std::to_string(spp)},
            {"seed", std::to_string(seed)},
            {"maxDepth", std::to_string(maxDepth)},
            {"camera", camera.empty() ? "(first)" : camera},
            {"timeLimit", std::to_string(timeLimit)}};
}

}  // namespace rs
