// A walkthrough's frames (walkthrough.h).
#include "walkthrough.h"

#include <algorithm>
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

// One rank of an MPI job rendering a whole frame by itself: a single process to the render,
// but sharing its machine's memory with the job's other ranks there (the memory check).
class AloneOnSharedMachine : public Ranks {
public:
    explicit AloneOnSharedMachine(int onThisMachine) : onThisMachine_(onThisMachine) {}
    int sizeOnThisMachine() const override { return onThisMachine_; }

private:
    int onThisMachine_;
};

}  // namespace

Walkthrough::Walkthrough(const RenderConfig& cfg, Reporter& reporter, Ranks& ranks)
    : cfg_(cfg), posedCfg_(cfg), reporter_(reporter), ranks_(ranks) {
    cfg.validate();
    Timer read;
    file_ = std::make_unique<SceneFile>(cfg.scene, reporter, cfg.threads);
    readSeconds_ = read.seconds();
    const Scene& rest = file_->scene();
    const SceneAnimation& animation = rest.animation;
    selected_ = animation.select(cfg.animation, cfg.scene);
    camerasOnly_ = animation.movesOnlyCameras(selected_);
    if (camerasOnly_ && cfg.splats()) store_ = std::make_unique<PhotonStore>();
    // Where meshes or lights move, each frame traces its own photons; their kernel scale is the
    // one a stored range uses (1 unless given), not probed frame by frame from each view.
    if (!camerasOnly_ && posedCfg_.kernelScale <= 0.f) posedCfg_.kernelScale = 1.f;
    cameraIndex_ = rest.cameraIndex(cfg.camera);  // throws naming it when there is none
    // Whole frames to ranks where there is one for each: the photons of a camera-only range
    // are then traced once a rank, not once a frame's share.
    wholeFrames_ = ranks.size() > 1 && cfg.frameCount() >= ranks.size();
    if (wholeFrames_) alone_ = std::make_unique<AloneOnSharedMachine>(ranks.sizeOnThisMachine());
    // The scene as read serves every frame: prepared now, so that a range whose kept photons do
    // not fit is refused before its first frame.
    if (camerasOnly_) prepared_ = std::make_unique<PreparedScene>(rest, cfg_, reporter_, frameRanks(), store_ != nullptr);

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

Camera posedCamera(const Scene& rest, int index, const std::string& which, const std::vector<Mat4>& pose) {
    if (index < 0) return rest.camera(which);
    const SceneAnimation& a = rest.animation;
    return placeCamera(rest.cameras[index], a.worldFrom(a.cameraNode[index], pose));
}

RenderResult Walkthrough::renderFrame(int frame) {
    const float t = frameTime(frame, cfg_.fps);
    const std::vector<Mat4> pose = file_->scene().animation.pose(selected_, t);
    RenderResult result;
    if (camerasOnly_) {
        // The scene as read and the photons of the frames before: only the camera is posed.
        result = prepared_->render(posedCamera(file_->scene(), cameraIndex_, cfg_.camera, pose), store_.get());
    } else {
        // Meshes or lights move: the nodes flattened at the frame's pose from the file as read,
        // and what depends on the geometry built for this frame alone.
        Timer flatten;
        const Scene& posed = file_->pose(pose);
        const double poseSeconds = flatten.seconds();
        result = PreparedScene(posed, posedCfg_, reporter_, frameRanks()).render(posed.camera(cfg_.camera));
        result.stats.seconds.insert(result.stats.seconds.begin(), {"pose", poseSeconds});
    }
    // The file is read once for the range: the first frame rendered counts it.
    result.stats.setCount("scene_reads", firstFrame_ ? 1 : 0);
    if (firstFrame_) result.stats.seconds.insert(result.stats.seconds.begin(), {"load", readSeconds_});
    firstFrame_ = false;
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

Walkthrough::FrameDone Walkthrough::doFrame(int frame, int left, double secondsLeft) {
    const RenderConfig fc = frameConfig(frame);
    bool exists = cfg_.skipExisting;
    std::error_code ec;
    for (const std::string* f : {&fc.output, &fc.png, &fc.statsJson})
        if (!f->empty()) exists = exists && std::filesystem::exists(*f, ec);
    // A frame divided between ranks: rank 0 decides what exists, and every rank skips alike.
    if (!wholeFrames_) exists = agreeOrStop(ranks_, exists);
    if (exists) return {FrameDone::kSkipped, 0, 0, 0};
    reporter_.frame(frame, left, secondsLeft);
    RenderResult result = renderFrame(frame);
    if (wholeFrames_ || ranks_.rank() == 0) writeOutputs(result, fc);
    return {FrameDone::kRendered, result.film.width, result.film.height, int64_t(result.stats.totalSeconds() * 1e6)};
}

// Rank 0 says what became of each frame of the round, in frame order.
void Walkthrough::reportRound(int firstOfRound, const std::vector<int64_t>& done) {
    for (size_t r = 0; 4 * r < done.size(); ++r) {
        const int frame = firstOfRound + int(r) * cfg_.frameStep;
        const int64_t* d = &done[4 * r];
        if (d[0] == FrameDone::kSkipped) reporter_.info("frame " + std::to_string(frame) + ": " + frameConfig(frame).output + " exists, skipped");
        if (d[0] != FrameDone::kRendered) continue;
        char line[96];
        const std::string rank = wholeFrames_ ? ", rank " + std::to_string(r) : "";
        std::snprintf(line, sizeof line, " (frame %d%s, %lldx%lld, %.2f s)", frame, rank.c_str(), (long long)d[1],
                      (long long)d[2], double(d[3]) * 1e-6);
        reporter_.info("wrote " + frameConfig(frame).output + line);
    }
}

int Walkthrough::run() {
    const int shares = wholeFrames_ ? ranks_.size() : 1, me = wholeFrames_ ? ranks_.rank() : 0;
    const int rounds = (cfg_.frameCount() + shares - 1) / shares;
    int rendered = 0, roundsRendered = 0;
    Timer clock;
    // Every rank read the file: no frame is written where one could not.
    if (wholeFrames_) agreeOrStop(ranks_, false);
    for (int round = 0; round < rounds; ++round) {
        throwIfStopped();
        const int firstOfRound = cfg_.firstFrame + round * shares * cfg_.frameStep, frame = firstOfRound + me * cfg_.frameStep;
        const double secondsLeft = roundsRendered > 0 ? clock.seconds() / roundsRendered * (rounds - round) : -1.0;
        const FrameDone done =
            frame <= cfg_.lastFrame ? doFrame(frame, (cfg_.lastFrame - frame) / cfg_.frameStep, secondsLeft) : FrameDone{};
        // Every frame of the round is written (by its rank, or by rank 0 where the ranks shared
        // it): the others learn here whether that failed, before the round's report.
        agreeOrStop(ranks_, false);
        std::vector<int64_t> all(4 * size_t(shares), 0);
        const int64_t mine[4] = {done.status, done.width, done.height, done.microseconds};
        std::copy(mine, mine + 4, all.begin() + 4 * me);
        if (wholeFrames_) ranks_.sumAtRoot(all);
        reportRound(firstOfRound, all);
        int renderedNow = 0;
        for (size_t r = 0; r < size_t(shares); ++r) renderedNow += all[4 * r] == FrameDone::kRendered;
        rendered += renderedNow;
        roundsRendered += renderedNow > 0;
    }
    return rendered;
}

}  // namespace rs
