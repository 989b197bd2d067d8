#include "config.h"

#include <cstdint>

#include "core/simd.h"

#include <cmath>
#include <filesystem>
#include <unistd.h>

#include "core/error.h"
#include "grid/occlusion_grid.h"

namespace rs {

const char* methodName(Method m) {
    switch (m) {
        case Method::Splat: return "splat";
        case Method::SplatNoVis: return "splat-novis";
        case Method::Path: return "path";
    }
    return "?";
}

Method parseMethod(const std::string& name) {
    if (name == "splat") return Method::Splat;
    if (name == "splat-novis") return Method::SplatNoVis;
    if (name == "path") return Method::Path;
    throw Error(ErrorKind::Config, "`method` " + name + ": unknown method (splat, splat-novis, path)");
}

const char* directMethodName(DirectMethod d) { return d == DirectMethod::Sample ? "sample" : "photons"; }

DirectMethod parseDirectMethod(const std::string& name) {
    if (name == "sample") return DirectMethod::Sample;
    if (name == "photons") return DirectMethod::Photons;
    throw Error(ErrorKind::Config, "`direct` " + name + ": unknown method (sample, photons)");
}

const char* visibilityName(Visibility v) {
    switch (v) {
        case Visibility::Auto: return "auto";
        case Visibility::Mask: return "mask";
        case Visibility::Rays: return "rays";
    }
    return "?";
}

Visibility parseVisibility(const std::string& name) {
    if (name == "auto") return Visibility::Auto;
    if (name == "mask") return Visibility::Mask;
    if (name == "rays") return Visibility::Rays;
    throw Error(ErrorKind::Config, "`visibility` " + name + ": unknown visibility (auto, mask, rays)");
}

bool parseCoverageAt(const std::string& name) {
    if (name == "samples") return true;
    if (name == "photons") return false;
    throw Error(ErrorKind::Config, "`coverage-at` " + name + ": unknown place (samples, photons)");
}

ClassTriple RenderConfig::photonSplit() const {
    ClassTriple out = split;
    if (!splitSet && directBySampling()) out[0] = 0.f;
    return out;
}

static void requireRange(const char* setting, double v, double lo, double hi) {
    if (!(v >= lo && v <= hi)) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "`%s` %g is out of range (%g..%g)", setting, v, lo, hi);
        throw Error(ErrorKind::Config, buf);
    }
}

void RenderConfig::validate() const {
    checkSimdEnvironment();
    requireRange("width", width, 0, kMaxImageSide);
    requireRange("height", height, 0, kMaxImageSide);
    if (width == 0 && height == 0) throw Error(ErrorKind::Config, "`width` and `height` cannot both be 0");
    requireRange("spp", spp, 0, 1 << 20);
    requireRange("photons", double(photons), 1, 1e9);
    double splitSum = 0.0;
    for (int c = 0; c < 3; ++c) {
        requireRange("split", split[c], 0, 1e6);
        requireRange("kernel-photons", kernelPhotons[c], 0.1, 1e6);
        requireRange("min-radius", minRadius[c], 0.01, 4096);
        requireRange("max-radius", maxRadius[c], minRadius[c], 4096);
        splitSum += split[c];
    }
    if (!(splitSum > 0.0)) throw Error(ErrorKind::Config, "`split` needs a positive share for some class");
    if (splitSet && directBySampling() && split[0] > 0.f)
        throw Error(ErrorKind::Config, "`split` gives direct photons a share, but `direct` sample (the default) computes "
                                       "direct light by light sampling: use `split` 0,I,C or `direct` photons");
    const ClassTriple used = photonSplit();
    if (!(used[0] + used[1] + used[2] > 0.f)) throw Error(ErrorKind::Config, "`split` needs a positive share for some class");
    requireRange("light-samples", lightSamples, 1, 4096);
    requireRange("direct-spp", directSpp, 0, 1 << 16);
    requireRange("coverage-probes", coverageProbes, 0, CoverageSettings::kMaxProbes);
    requireRange("min-coverage", minCoverage, 0, 1);
    requireRange("receiver-spacing", receiverSpacing, 0, 4);
    requireRange("photon-rounds", photonRounds, 0, kMaxPhotonRounds);
    requireRange("passes", passes, 0, 1 << 20);
    requireRange("alpha", alpha, 0.01, 1);
    if (kernelScale != 0.f) requireRange("kernel-scale", kernelScale, 0.05, 4);
    requireRange("max-depth", maxDepth, 1, 1024);
    requireRange("threads", threads, 0, 1024);
    requireRange("time-limit", timeLimit, 0, 1e7);
    requireRange("film-passes", filmPasses, 0, 1 << 20);
    if (filmPasses > 0 && (!splats() || !directBySampling() || directSpp <= 0))
        throw Error(ErrorKind::Config, "`film-passes` adds passes of the direct film: only with a splat method, `direct` sample "
                                       "and `direct-spp` above 0");
    if (filmPasses > 0 && timeLimit > 0.0)
        throw Error(ErrorKind::Config, "`film-passes` gives a number of film passes; with `time-limit` the time left after the "
                                       "last whole pass goes to them by itself");
    requireRange("exposure", exposure, -50, 50);
    requireRange("env-strength", envStrength, 0, 1e9);
    requireRange("env-rotation", envRotation, -36000, 36000);
    for (int c = 0; c < 3; ++c) requireRange("sky", sky[c], 0, 1e9);
    if (!env.empty() && !isBlack(sky)) throw Error(ErrorKind::Config, "`env` and `sky` both give an environment: choose one");
    std::error_code envError;
    if (!env.empty() && !std::filesystem::is_regular_file(env, envError)) throw Error(ErrorKind::Io, env + ": no such file");
    if (replays() && (method == Method::Path || timeLimit > 0.0))
        throw Error(ErrorKind::Config, "`photon` replays one photon ray of one pass of a splat render: not with `method` path "
                                       "or `time-limit`");
    if (replays() && passes > 0 && replayPass >= passes)
        throw Error(ErrorKind::Config, "`photon` " + std::to_string(replayPass) + ":" + std::to_string(replayIndex) +
                                           ": a render of " + std::to_string(passes) + " passes has no pass " +
                                           std::to_string(replayPass));
    if (replays()) requireRange("photon", double(replayIndex), 0, 1e12);
    if (replays() && photonRounds > 1)
        throw Error(ErrorKind::Config, "`photon` replays a ray of a pass of one photon round: not with `photon-rounds` above 1");
    if (blenderLayer.find_first_of(".\n") != std::string::npos)
        throw Error(ErrorKind::Config, "`blender-layer` '" + blenderLayer + "' names a view layer: no '.' in it");
    validateGrid();
    validateFrames();
    if (output.empty()) throw Error(ErrorKind::Config, "no output file: give `output` FILE.exr");
    // Refuse before rendering, not after: every output's directory must exist.
    for (const std::string* f : {&output, &png, &statsJson}) {
        if (f->empty()) continue;
        std::filesystem::path dir = std::filesystem::path(*f).parent_path();
        std::error_code ec;
        if (!dir.empty() && !std::filesystem::is_directory(dir, ec))
            throw Error(ErrorKind::Io, *f + ": directory " + dir.string() + " does not exist");
    }
    if (timeLimit <= 0.0 && passCount() + filmPasses > maxPasses())
        throw Error(ErrorKind::Config, "`passes` " + std::to_string(passCount() + filmPasses) +
                                           " × the samples a pixel of a pass count past 2^31 (at most " +
                                           std::to_string(maxPasses()) + " passes, film passes included)");
    double pixels = double(width ? width : height) * double(height ? height : width);
    if (pixels * samplesPerPixel() > 1e12) throw Error(ErrorKind::Config, "`width` × `height` × `spp` is absurdly large");
}

void RenderConfig::validateFrames() const {
    requireRange("fps", fps, 0.001, 1000);
    if (!walkthrough()) {
        if (!animation.empty()) throw Error(ErrorKind::Config, "`animation` picks what `frames` renders: give `frames` too");
        if (skipExisting) throw Error(ErrorKind::Config, "`skip-existing` skips the frames of `frames`: give `frames` too");
        if (frameStep != 1) throw Error(ErrorKind::Config, "`frame-step` steps through the frames of `frames`: give `frames` too");
        return;
    }
    const std::string range = std::to_string(firstFrame) + "-" + std::to_string(lastFrame);
    if (lastFrame < firstFrame) throw Error(ErrorKind::Config, "`frames` " + range + " is reversed: the first frame comes after the last");
    if (lastFrame > kMaxFrame) throw Error(ErrorKind::Config, "`frames` " + range + ": frames go up to " + std::to_string(kMaxFrame));
    if (frameStep < 1 || frameStep > kMaxFrame)
        throw Error(ErrorKind::Config, "`frame-step` " + std::to_string(frameStep) + " is out of range (1.." + std::to_string(kMaxFrame) + ")");
    if (!vdb.empty()) throw Error(ErrorKind::Config, "`vdb` writes one grid: not with `frames`");
    if (replays()) throw Error(ErrorKind::Config, "`photon` replays a ray of a still: not with `frames`");
    // A walkthrough writes for a long time: refuse a folder it cannot write to before its first frame.
    for (const std::string* f : {&output, &png, &statsJson}) {
        const std::filesystem::path dir = std::filesystem::path(*f).parent_path();
        std::error_code ec;
        const std::string d = dir.empty() ? "." : dir.string();
        if (!f->empty() && std::filesystem::is_directory(d, ec) && access(d.c_str(), W_OK) != 0)
            throw Error(ErrorKind::Io, *f + ": directory " + d + " cannot be written");
    }
}

int RenderConfig::maxPasses() const {
    const int64_t perPass = std::max<int64_t>({samplesPerPixel(), directSpp, 1});
    return int(std::min<int64_t>(INT32_MAX / perPass, INT32_MAX));
}

Environment RenderConfig::environment(const Scene& scene) const {
    if (!env.empty()) return loadEnvironment(env, envStrength, envRotation * kPi / 180.f);
    if (!isBlack(sky)) return Environment::uniform(sky);
    const Scene::EnvironmentSettings& own = scene.environment;
    if (!own.file.empty()) return loadEnvironment(own.file, own.strength, own.rotation * kPi / 180.f);
    return Environment::uniform(own.sky);
}

void RenderConfig::validateGrid() const {
    requireRange("grid", grid, 1, kMaxGridResolution);
    if (voxelizer != "auto" && voxelizer != "gpu" && voxelizer != "cpu")
        throw Error(ErrorKind::Config, "`voxelizer` " + voxelizer + ": unknown voxelizer (auto, gpu, cpu)");
    if (!vdb.empty()) {
        std::filesystem::path dir = std::filesystem::path(vdb).parent_path();
        std::error_code ec;
        if (!dir.empty() && !std::filesystem::is_directory(dir, ec))
            throw Error(ErrorKind::Io, vdb + ": directory " + dir.string() + " does not exist");
    }
}

void RenderConfig::resolution(float aspect, int& w, int& h) const {
    if (!(aspect > 0.f) || !std::isfinite(aspect)) aspect = 1.f;
    w = width;
    h = height;
    if (w == 0) w = std::max(1, int(std::lround(h * aspect)));
    if (h == 0) h = std::max(1, int(std::lround(w / aspect)));
    if (w > kMaxImageSide || h > kMaxImageSide)
        throw Error(ErrorKind::Config, "resolution " + std::to_string(w) + "x" + std::to_string(h) + " from the camera's aspect is too large");
}

std::string tripleText(const ClassTriple& v) {
    char b[96];
    std::snprintf(b, sizeof b, "%g,%g,%g", v[0], v[1], v[2]);
    return b;
}

std::string numberText(float v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return b;
}

ImageAttributes RenderConfig::attributes() const {
    ImageAttributes a = {{"method", methodName(method)},
            {"spp", std::to_string(samplesPerPixel())},
            {"seed", std::to_string(seed)},
            {"maxDepth", std::to_string(maxDepth)},
            {"camera", camera.empty() ? "(first)" : camera},
            {"timeLimit", std::to_string(timeLimit)},
            {"passes", std::to_string(passCount())},
            {"grid", std::to_string(grid)},
            {"voxelizer", voxelizer}};
    if (!env.empty()) {
        a["env"] = env;
        a["envStrength"] = std::to_string(envStrength);
        a["envRotation"] = std::to_string(envRotation);
    }
    if (!isBlack(sky)) a["sky"] = tripleText({sky.x, sky.y, sky.z});
    if (walkthrough()) {
        a["fps"] = numberText(fps);
        a["animation"] = animation.empty() ? "(all)" : animation;
    }
    if (splats()) {
        const ClassTriple used = photonSplit();
        a["direct"] = directMethodName(direct);
        if (directBySampling()) a["lightSamples"] = std::to_string(lightSamples);
        if (directBySampling()) a["directSpp"] = std::to_string(directSpp);
        if (filmPasses > 0) a["filmPasses"] = std::to_string(filmPasses);
        a["alpha"] = std::to_string(alpha);
        a["kernelScale"] = kernelScale > 0.f ? std::to_string(kernelScale) : probesKernelScale() ? "auto" : "1";
        a["photons"] = std::to_string(photons);
        a["photonRounds"] = photonRounds > 0 ? std::to_string(photonRounds) : photonRoundsAuto() ? "auto" : "1";
        a["split"] = tripleText(used);
        a["kernelPhotons"] = tripleText(kernelPhotons);
        a["radiusVoxels"] = tripleText(minRadius) + "/" + tripleText(maxRadius);
        if (method == Method::Splat) {
            a["visibility"] = visibilityName(visibilityUsed());
            if (visibilityUsed() == Visibility::Rays) a["coverageProbes"] = std::to_string(coverageProbes);
            if (visibilityUsed() == Visibility::Rays) a["minCoverage"] = std::to_string(minCoverage);
            if (visibilityUsed() == Visibility::Rays) a["coverageAt"] = coverageAtSamples ? "samples" : "photons";
            if (visibilityUsed() == Visibility::Rays) a["receiverSpacing"] = numberText(receiverSpacing);
        }
    }
    return a;
}

}  // namespace rs
