// The reporters (reporters.h).
#include "reporters.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <mutex>

#include "core/parallel.h"
#include "core/stats.h"

namespace rs::cli {

// The library names settings in backticks (`spp`); on the command line they are flags, spelt
// the same with two dashes (the output file: -o).
std::string withFlags(const std::string& message) {
    std::string out;
    for (size_t i = 0; i < message.size(); ++i) {
        const size_t end = message[i] == '`' ? message.find('`', i + 1) : std::string::npos;
        if (end == std::string::npos) {
            out += message[i];
            continue;
        }
        const std::string name = message.substr(i + 1, end - i - 1);
        out += name == "output" ? "-o" : "--" + name;
        i = end;
    }
    return out;
}

namespace {

// Stages nest one level: the render's passes are the outer stage, each pass's stages (eye pass,
// photons, splatting) the inner one.
struct Progress {
    std::string stage;
    const char* unit = "";
    int64_t total = 0, done = 0;  // total 0: open-ended (passes under a time limit)
    bool hasInner = false;        // stages ran inside it
    Timer timer;
    void start(const std::string& s, int64_t t, const char* u) {
        stage = s, unit = u, total = t, done = 0, hasInner = false, timer = Timer();
    }
    double fraction() const { return total > 0 ? std::min(1.0, double(done) / double(total)) : 0.0; }
};

struct Nesting {
    int depth = 0;
    Progress outer, inner;
    // Returns whether the stage is the inner one.
    bool begin(const std::string& stage, int64_t total, const char* unit) {
        const bool nested = depth == 1;
        depth = std::min(depth + 1, 2);
        (nested ? inner : outer).start(stage, total, unit);
        if (nested) outer.hasInner = true;
        return nested;
    }
    Progress& current() { return depth == 2 ? inner : outer; }
    bool end() {
        const bool nested = depth == 2;
        depth = std::max(depth - 1, 0);
        return nested;
    }
    // The outer stage's share done, the current unit's inner progress counted as a part of one unit.
    double fraction() const {
        return outer.total > 0 ? std::min(1.0, (double(outer.done) + (depth == 2 ? inner.fraction() : 0.0)) / double(outer.total)) : 0.0;
    }
};

// A progress bar on a TTY, plain lines otherwise, nothing with --quiet. Only the outer stage
// prints lines.
class ConsoleReporter : public Reporter {
public:
    explicit ConsoleReporter(bool quiet) : quiet_(quiet), tty_(isatty(STDERR_FILENO)) {}

    void info(const std::string& m) override {
        if (quiet_) return;
        std::lock_guard<std::mutex> lock(mutex_);
        clearBar();
        std::fprintf(stderr, "raysplat: %s\n", withFlags(m).c_str());
    }
    void warn(const std::string& m) override {
        std::lock_guard<std::mutex> lock(mutex_);
        clearBar();
        std::fprintf(stderr, "raysplat: warning: %s\n", withFlags(m).c_str());
    }
    void begin(const std::string& stage, int64_t total, const char* unit) override {
        std::lock_guard<std::mutex> lock(mutex_);
        const bool nested = n_.begin(stage, total, unit);
        if (!quiet_ && !tty_ && !nested) {
            if (total > 0) std::fprintf(stderr, "raysplat: %s: %lld %s\n", stage.c_str(), (long long)total, unit);
            else std::fprintf(stderr, "raysplat: %s\n", stage.c_str());
        }
    }
    void advance(int64_t units) override {
        std::lock_guard<std::mutex> lock(mutex_);
        Progress& p = n_.current();
        p.done += units;
        if (quiet_) return;
        if (!tty_) {
            if (n_.depth == 1 && p.hasInner)  // a line per unit of work made of stages
                std::fprintf(stderr, "raysplat: %s: pass %lld%s done, %.1f s\n", p.stage.c_str(), (long long)p.done,
                             p.total > 0 ? fmtTotal(p.total).c_str() : "", p.timer.seconds());
            return;
        }
        double now = n_.outer.timer.seconds();
        if (now - lastDraw_ < 0.1 && p.done < p.total) return;
        lastDraw_ = now;
        drawBar();
    }
    void frame(int frame, int left, double secondsLeft) override {
        std::lock_guard<std::mutex> lock(mutex_);
        if (quiet_) return;
        clearBar();
        char eta[48] = "";
        if (secondsLeft >= 0.0) std::snprintf(eta, sizeof eta, ", about %.0f s left", secondsLeft);
        std::fprintf(stderr, "raysplat: frame %d (%d more after it%s)\n", frame, left, eta);
    }
    void end() override {
        std::lock_guard<std::mutex> lock(mutex_);
        const bool nested = n_.end();
        if (quiet_ || nested) return;
        clearBar();
        std::fprintf(stderr, "raysplat: %s done in %.2f s\n", n_.outer.stage.c_str(), n_.outer.timer.seconds());
    }

private:
    static std::string fmtTotal(int64_t total) { return "/" + std::to_string(total); }

    void drawBar() {
        const int width = 30;
        const Progress& o = n_.outer;
        std::string line = "\r\033[Kraysplat: " + o.stage;
        char buf[256];
        if (o.total > 0) {
            // The outer bar counts the current unit's inner progress as a fraction of one unit.
            double f = n_.fraction();
            int fill = int(f * width);
            double eta = f > 0.0 ? o.timer.seconds() * (1.0 - f) / f : 0.0;
            std::snprintf(buf, sizeof buf, " [%.*s%*s] %3d%% %lld/%lld %s, %.1f s left", fill,
                          "##############################", width - fill, "", int(f * 100), (long long)o.done,
                          (long long)o.total, o.unit, eta);
        } else {
            std::snprintf(buf, sizeof buf, " %lld %s, %.1f s", (long long)o.done, o.unit, o.timer.seconds());
        }
        line += buf;
        if (n_.depth == 2) {
            std::snprintf(buf, sizeof buf, " · %s %3d%%", n_.inner.stage.c_str(), int(n_.inner.fraction() * 100));
            line += buf;
        }
        std::fputs(line.c_str(), stderr);
        std::fflush(stderr);
        barShown_ = true;
    }
    void clearBar() {
        if (barShown_) std::fprintf(stderr, "\r\033[K");
        barShown_ = false;
    }

    bool quiet_, tty_;
    std::mutex mutex_;
    Nesting n_;
    double lastDraw_ = -1.0;
    bool barShown_ = false;
};


// One JSON object a line: begin and end of every stage, progress at most every 0.1 s (and at the
// end of each outer unit), info and warnings. Written whole under a lock, so lines never mix.
class JsonReporter : public Reporter {
public:
    void info(const std::string& m) override { line("{\"event\": \"info\", \"message\": " + jsonString(withFlags(m)) + "}"); }
    void warn(const std::string& m) override { line("{\"event\": \"warning\", \"message\": " + jsonString(withFlags(m)) + "}"); }
    void begin(const std::string& stage, int64_t total, const char* unit) override {
        std::lock_guard<std::mutex> lock(mutex_);
        n_.begin(stage, total, unit);
        write("{\"event\": \"begin\", \"stage\": " + jsonString(stage) + ", \"total\": " + std::to_string(total) +
              ", \"unit\": " + jsonString(unit) + ", \"depth\": " + std::to_string(n_.depth) + "}");
    }
    void advance(int64_t units) override {
        std::lock_guard<std::mutex> lock(mutex_);
        Progress& p = n_.current();
        p.done += units;
        const double now = clock_.seconds();
        const bool unitDone = n_.depth == 1;
        if (!unitDone && now - last_ < 0.1) return;
        last_ = now;
        // The inner stages of a unit do not know their share of it: "fraction" counts whole units
        // (0 while open-ended), "inner_fraction" the current inner stage.
        char buf[160];
        std::snprintf(buf, sizeof buf, ", \"done\": %lld, \"total\": %lld, \"fraction\": %.4f, \"seconds\": %.3f",
                      (long long)n_.outer.done, (long long)n_.outer.total, n_.outer.fraction(), n_.outer.timer.seconds());
        std::string inner;
        if (n_.depth == 2) {
            char f[48];
            std::snprintf(f, sizeof f, ", \"inner_fraction\": %.4f", n_.inner.fraction());
            inner = ", \"inner\": " + jsonString(n_.inner.stage) + f;
        }
        write("{\"event\": \"progress\", \"stage\": " + jsonString(n_.outer.stage) + buf + inner + "}");
    }
    void end() override {
        std::lock_guard<std::mutex> lock(mutex_);
        const Progress& p = n_.current();
        char buf[64];
        std::snprintf(buf, sizeof buf, ", \"seconds\": %.3f", p.timer.seconds());
        write("{\"event\": \"end\", \"stage\": " + jsonString(p.stage) + buf + ", \"depth\": " + std::to_string(n_.depth) + "}");
        n_.end();
    }

    // From a walkthrough's first frame on, every event says which frame it belongs to.
    void frame(int frame, int left, double secondsLeft) override {
        std::lock_guard<std::mutex> lock(mutex_);
        frame_ = frame;
        char buf[96];
        std::snprintf(buf, sizeof buf, "{\"event\": \"frame\", \"left\": %d, \"seconds_left\": %.3f}", left, secondsLeft);
        write(buf);
    }

private:
    void line(const std::string& text) {
        std::lock_guard<std::mutex> lock(mutex_);
        write(text);
    }
    void write(const std::string& text) const {
        const std::string withFrame = frame_ < 0 ? text : "{\"frame\": " + std::to_string(frame_) + ", " + text.substr(1);
        std::fprintf(stderr, "%s\n", withFrame.c_str());
        std::fflush(stderr);
    }
    int frame_ = -1;
    std::mutex mutex_;
    Nesting n_;
    Timer clock_;
    double last_ = -1.0;
};

}  // namespace

std::unique_ptr<Reporter> makeReporter(bool quiet, bool json) {
    if (json) return std::make_unique<JsonReporter>();
    return std::make_unique<ConsoleReporter>(quiet);
}

void reportDone(bool json, const std::string& output, double seconds) {
    if (!json) return;
    char buf[64];
    std::snprintf(buf, sizeof buf, ", \"seconds\": %.3f}", seconds);
    std::fprintf(stderr, "{\"event\": \"done\", \"output\": %s%s\n", jsonString(output).c_str(), buf);
    std::fflush(stderr);
}

}  // namespace rs::cli
