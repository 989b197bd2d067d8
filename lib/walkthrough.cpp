// A walkthrough's frames (walkthrough.h).
#include "walkthrough.h"

#include <cstdio>
#include <filesystem>

#include "core/error.h"
#include "core/stop.h"
#include "render_context.h"
#include "splat_pass.h"

namespace rs {

std::string framePath(const std::string& pattern, int frame, bool several) {
    const size_t nameStart = pattern.find_last_of('/') == std::string::npos ? 0 : pattern.find_last_of('/') + 1;
    const size_t last = pattern.find_last_of('#');
    if (last != std::string::npos && last >= nameStart) {
        size_t first = last;
        while (first > nameStart && pattern[first - 1] == '#') --first;
        std::string number = std::to_string(frame);
        if (number.size() < last + 1 - first) number.insert(0, last + 1 - first - number.size(), '0');
        return pattern.substr(0, first) + number + pattern.substr(last + 1);
    }
    if (!several) return pattern;
    char number[16];
    std::snprintf(number, sizeof number, "_%04d", frame);
    const size_t dot = pattern.find_last_of('.');
    const size_t at = dot != std::string::npos && dot > nameStart ? dot : pattern.size();
    return pattern.substr(0, at) + number + pattern.substr(at);
}

namespace {

std::string seconds(float t) {
    char b[32];
    std::snprintf(b, sizeof b, "%.4g s", t);
    return b;
}

}  // namespace

Walkthrough::Walkthrough(const RenderConfig& cfg, Reporter& reporter, Ranks& ranks)
    : cfg_(cfg), reporter_(reporter), ranks_(ranks), rest_(loadScene(cfg.scene, reporter, cfg.threads)) {
    cfg.validate();
    const SceneAnimation& animation = rest_.animation;
    selected_ = animation.select(cfg.animation, cfg.scene);
    camerasOnly_ = animation.movesOnlyCameras(selected_);
    if (camerasOnly_ && cfg.splats()) store_ = std::make_unique<PhotonStore>();
    cameraIndex_ = rest_.cameraIndex(cfg.camera);  // throws naming it when there is none

    // What the range shows that the user may not expect: warnings, once.
    if (!animation.unsupported.empty())
        reporter.warn(cfg.scene + ": " + animation.unsupported + " are not animated: rendered in their rest pose");
    if (selected_.empty()) {
        reporter.warn(cfg.scene + ": the file has no animations: every frame is the same still");
        return;
    }
    const float start = animation.start(selected_), end = animation.end(selected_);
    const float first = float(cfg.firstFrame) / cfg.fps, last = float(cfg.lastFrame) / cfg.fps;
    const std::string range = "frames " + std::to_string(cfg.firstFrame) + "-" + std::to_string(cfg.lastFrame);
    if (last > end)
        reporter.warn(cfg.scene + ": " + range + " (to " + seconds(last) + ") go past the animation's end at " + seconds(end) +
                      ": its last pose is held");
    if (first < start)
        reporter.warn(cfg.scene + ": " + range + " (from " + seconds(first) + ") begin before the animation's start at " +
                      seconds(start) + ": its first pose is held");
}

Walkthrough::~Walkthrough() = default;

Camera Walkthrough::cameraAt(const std::vector<Mat4>& pose) const {
    if (cameraIndex_ < 0) return rest_.camera(cfg_.camera);  // the framing camera does not move
    const SceneAnimation& a = rest_.animation;
    return placeCamera(rest_.cameras[cameraIndex_], a.worldFrom(a.cameraNode[cameraIndex_], pose));
}

RenderResult Walkthrough::renderFrame(int frame) {
    const float t = float(frame) / cfg_.fps;
    const std::vector<Mat4> pose = rest_.animation.pose(selected_, t);
    RenderResult result;
    if (camerasOnly_) {
        // The scene as loaded and the photons of the frames before: only the camera is posed.
        if (!prepared_) prepared_ = std::make_unique<PreparedScene>(rest_, cfg_, reporter_, ranks_);
        result = prepared_->render(cameraAt(pose), store_.get());
    } else {
        // Meshes or lights move: the frame's own scene, flattened as posed (its warnings were the
        // rest scene's).
        Timer load;
        const Scene posed = loadScene(cfg_.scene, silentReporter(), cfg_.threads, &pose);
        const double loadSeconds = load.seconds();
        result = PreparedScene(posed, cfg_, reporter_, ranks_).render(posed.camera(cfg_.camera));
        result.stats.seconds.insert(result.stats.seconds.begin(), {"load", loadSeconds});
    }
    result.stats.setCount("frame", frame);
    result.attributes["frame"] = std::to_string(frame);
    result.attributes["time"] = std::to_string(t);
    return result;
}

RenderConfig Walkthrough::frameConfig(int frame) const {
    RenderConfig c = cfg_;
    const bool several = cfg_.lastFrame > cfg_.firstFrame;
    c.output = framePath(cfg_.output, frame, several);
    if (!c.png.empty()) c.png = framePath(cfg_.png, frame, several);
    if (!c.statsJson.empty()) c.statsJson = framePath(cfg_.statsJson, frame, several);
    return c;
}

int Walkthrough::run() {
    const bool root = ranks_.rank() == 0;
    int rendered = 0;
    Timer clock;
    for (int frame = cfg_.firstFrame; frame <= cfg_.lastFrame; ++frame) {
        throwIfStopped();
        const RenderConfig fc = frameConfig(frame);
        // Rank 0 decides what exists; every rank skips alike.
        bool exists = cfg_.skipExisting;
        std::error_code ec;
        for (const std::string* f : {&fc.output, &fc.png, &fc.statsJson})
            if (!f->empty()) exists = exists && std::filesystem::exists(*f, ec);
        if (agreeOrStop(ranks_, exists)) {
            reporter_.info("frame " + std::to_string(frame) + ": " + fc.output + " exists, skipped");
            continue;
        }
        const int left = cfg_.lastFrame - frame;
        reporter_.frame(frame, left, rendered > 0 ? clock.seconds() / rendered * (left + 1) : -1.0);
        RenderResult result = renderFrame(frame);
        if (root) writeOutputs(result, fc);
        // Rank 0 wrote the frame: the others learn here whether that failed.
        agreeOrStop(ranks_, false);
        ++rendered;
        char line[64];
        std::snprintf(line, sizeof line, " (frame %d, %dx%d, %.2f s)", frame, result.film.width, result.film.height,
                      result.stats.totalSeconds());
        if (root) reporter_.info("wrote " + fc.output + line);
    }
    return rendered;
}

}  // namespace rs
