// The raysplat command: argument parsing, console log and progress. The only place that
// catches rs::Error: it prints "raysplat: error: …" on one line and exits with 1.
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdarg>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "error.h"
#include "log.h"
#include "render.h"
#include "scene.h"
#include "stats.h"

using namespace rs;

namespace {

// -- Console reporter: a progress bar on a TTY, plain lines otherwise, nothing with --quiet.
class ConsoleReporter : public Reporter {
public:
    explicit ConsoleReporter(bool quiet) : quiet_(quiet), tty_(isatty(STDERR_FILENO)) {}

    void info(const std::string& m) override {
        if (quiet_) return;
        std::lock_guard<std::mutex> lock(mutex_);
        clearBar();
        std::fprintf(stderr, "raysplat: %s\n", m.c_str());
    }
    void warn(const std::string& m) override {
        std::lock_guard<std::mutex> lock(mutex_);
        clearBar();
        std::fprintf(stderr, "raysplat: warning: %s\n", m.c_str());
    }
    void begin(const std::string& stage, int64_t total, const char* unit) override {
        std::lock_guard<std::mutex> lock(mutex_);
        stage_ = stage;
        unit_ = unit;
        total_ = std::max<int64_t>(total, 1);
        done_ = 0;
        shown_ = -1;
        timer_ = Timer();
        lastDraw_ = -1.0;
        if (!quiet_ && !tty_) std::fprintf(stderr, "raysplat: %s: %lld %s\n", stage.c_str(), (long long)total, unit);
    }
    void advance(int64_t units) override {
        int64_t done = done_.fetch_add(units) + units;
        if (quiet_ || !tty_) return;
        std::lock_guard<std::mutex> lock(mutex_);
        double now = timer_.seconds();
        if (now - lastDraw_ < 0.1 && done < total_) return;
        lastDraw_ = now;
        drawBar(done);
    }
    void end() override {
        if (quiet_) return;
        std::lock_guard<std::mutex> lock(mutex_);
        clearBar();
        std::fprintf(stderr, "raysplat: %s done in %.2f s\n", stage_.c_str(), timer_.seconds());
    }

private:
    void drawBar(int64_t done) {
        const int width = 30;
        double f = std::min(1.0, double(done) / double(total_));
        int fill = int(f * width);
        double eta = f > 0.0 ? timer_.seconds() * (1.0 - f) / f : 0.0;
        std::fprintf(stderr, "\r\033[Kraysplat: %s [%.*s%*s] %3d%% %lld/%lld %s, %.1f s left", stage_.c_str(), fill,
                     "##############################", width - fill, "", int(f * 100), (long long)done,
                     (long long)total_, unit_, eta);
        std::fflush(stderr);
        barShown_ = true;
    }
    void clearBar() {
        if (barShown_) std::fprintf(stderr, "\r\033[K");
        barShown_ = false;
    }

    bool quiet_, tty_;
    std::mutex mutex_;
    std::string stage_;
    const char* unit_ = "";
    int64_t total_ = 1;
    std::atomic<int64_t> done_{0};
    int64_t shown_ = -1;
    Timer timer_;
    double lastDraw_ = -1.0;
    bool barShown_ = false;
};

// -- Arguments --------------------------------------------------------------------------------

struct Option {
    std::string name;  // "--spp"
    std::string arg;   // "N", or "" for a switch
    std::string help;
    std::function<void(const std::string&)> set;
};

template <class T>
T parseNumber(const std::string& flag, const std::string& s) {
    T v{};
    const char* end = s.data() + s.size();
    auto [p, ec] = std::from_chars(s.data(), end, v);
    if (ec != std::errc() || p != end || s.empty())
        throw Error(ErrorKind::Config, flag + ": '" + s + "' is not a valid number");
    return v;
}

float parseFloat(const std::string& flag, const std::string& s) {
    char* end = nullptr;
    float v = std::strtof(s.c_str(), &end);
    if (s.empty() || *end != '\0' || !std::isfinite(v)) throw Error(ErrorKind::Config, flag + ": '" + s + "' is not a valid number");
    return v;
}

class Command {
public:
    Command(std::string usage, std::string summary) : usage_(std::move(usage)), summary_(std::move(summary)) {}
    void add(Option o) { options_.push_back(std::move(o)); }

    // Returns the positional arguments; handles --help.
    std::vector<std::string> parse(int argc, char** argv, int first, bool& helpShown) {
        std::vector<std::string> positional;
        helpShown = false;
        for (int i = first; i < argc; ++i) {
            std::string a = argv[i];
            if (a == "-h" || a == "--help") { printHelp(); helpShown = true; return {}; }
            if (a.size() > 1 && a[0] == '-' && !(a.size() > 1 && std::isdigit(static_cast<unsigned char>(a[1])))) {
                std::string name = a, value;
                bool inlineValue = false;
                if (auto eq = a.find('='); eq != std::string::npos) { name = a.substr(0, eq); value = a.substr(eq + 1); inlineValue = true; }
                const Option* o = find(name);
                if (!o) throw Error(ErrorKind::Config, "unknown option '" + name + "' (see --help)");
                if (!o->arg.empty() && !inlineValue) {
                    if (i + 1 >= argc) throw Error(ErrorKind::Config, name + " needs a value: " + name + " " + o->arg);
                    value = argv[++i];
                }
                o->set(value);
            } else {
                positional.push_back(a);
            }
        }
        return positional;
    }

    void printHelp() const {
        std::printf("usage: %s\n\n%s\n\noptions:\n", usage_.c_str(), summary_.c_str());
        for (const Option& o : options_) {
            std::string left = o.name + (o.arg.empty() ? "" : " " + o.arg);
            std::printf("  %-22s %s\n", left.c_str(), o.help.c_str());
        }
        std::printf("  %-22s %s\n", "-h, --help", "show this help");
    }

private:
    const Option* find(const std::string& name) const {
        for (const Option& o : options_)
            if (o.name == name || (o.name == "--output" && name == "-o")) return &o;
        return nullptr;
    }
    std::string usage_, summary_;
    std::vector<Option> options_;
};

const char* kTopHelp =
    "usage: raysplat <command> [options]\n"
    "\n"
    "Global illumination for glTF 2.0 scenes by photon ray splatting (Herzog & Seidel 2007).\n"
    "\n"
    "commands:\n"
    "  render SCENE -o OUT.exr   render a .gltf/.glb scene to OpenEXR (and a PNG preview)\n"
    "  info SCENE                triangles, materials, lights, emitted power, camera, bounds\n"
    "  voxelize SCENE -o G.vdb   voxelize the scene into an occlusion grid (not built yet)\n"
    "\n"
    "Run 'raysplat <command> --help' for the options of a command.\n";

std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* f, ...) {
    char buf[1024];
    va_list ap;
    va_start(ap, f);
    std::vsnprintf(buf, sizeof buf, f, ap);
    va_end(ap);
    return buf;
}

std::string vec(const Vec3& v) { return fmt("(%.4g, %.4g, %.4g)", v.x, v.y, v.z); }

int cmdRender(int argc, char** argv) {
    RenderConfig cfg;
    bool quiet = false;
    Command cmd("raysplat render SCENE -o OUT.exr [options]",
                "Renders SCENE (.gltf or .glb) and writes a float OpenEXR with the beauty image and the layers\n"
                "direct, indirect, caustic, emission, albedo and normal. Outputs are written atomically: a failed\n"
                "run leaves no file behind.");
    cmd.add({"--output", "FILE", "OpenEXR output (also -o)", [&](const std::string& v) { cfg.output = v; }});
    cmd.add({"--png", "FILE", "also write a tone-mapped sRGB PNG preview", [&](const std::string& v) { cfg.png = v; }});
    cmd.add({"--stats-json", "FILE", "write per-stage times and counts as JSON", [&](const std::string& v) { cfg.statsJson = v; }});
    cmd.add({"--method", "NAME", "path (reference path tracer); splat methods: not built yet", [&](const std::string& v) { cfg.method = parseMethod(v); }});
    cmd.add({"--width", "N", "image width in pixels (default 500; 0: from --height and the camera aspect)",
             [&](const std::string& v) { cfg.width = parseNumber<int>("--width", v); }});
    cmd.add({"--height", "N", "image height (default: from the width and the camera's aspect ratio)",
             [&](const std::string& v) { cfg.height = parseNumber<int>("--height", v); }});
    cmd.add({"--spp", "N", "samples per pixel (default 16; per pass with --time-limit)",
             [&](const std::string& v) { cfg.spp = parseNumber<int>("--spp", v); }});
    cmd.add({"--max-depth", "N", "longest path, in vertices (default 32)",
             [&](const std::string& v) { cfg.maxDepth = parseNumber<int>("--max-depth", v); }});
    cmd.add({"--time-limit", "SECONDS", "render passes of --spp until the time is up, then average",
             [&](const std::string& v) { cfg.timeLimit = parseFloat("--time-limit", v); }});
    cmd.add({"--camera", "NAME", "the glTF camera to use (default: the first one)", [&](const std::string& v) { cfg.camera = v; }});
    cmd.add({"--seed", "N", "seed of every random sequence (default 0)", [&](const std::string& v) { cfg.seed = parseNumber<uint64_t>("--seed", v); }});
    cmd.add({"--threads", "N", "worker threads (default 0: all cores); the image does not depend on it",
             [&](const std::string& v) { cfg.threads = parseNumber<int>("--threads", v); }});
    cmd.add({"--exposure", "STOPS", "exposure of the PNG preview (default 0)", [&](const std::string& v) { cfg.exposure = parseFloat("--exposure", v); }});
    cmd.add({"--quiet", "", "no progress or messages, only errors and warnings", [&](const std::string&) { quiet = true; }});
    bool help;
    std::vector<std::string> pos = cmd.parse(argc, argv, 2, help);
    if (help) return 0;
    if (pos.size() != 1) throw Error(ErrorKind::Config, "render needs exactly one SCENE (see raysplat render --help)");
    cfg.scene = pos[0];
    cfg.validate();

    ConsoleReporter reporter(quiet);
    Timer load;
    Scene scene = loadScene(cfg.scene, reporter);
    double loadSeconds = load.seconds();
    RenderResult result = render(scene, cfg, reporter);
    result.stats.seconds.insert(result.stats.seconds.begin(), {"load", loadSeconds});
    writeOutputs(result, cfg);
    reporter.info(fmt("wrote %s (%dx%d, %s, %.2f s)", cfg.output.c_str(), result.film.width, result.film.height,
                      methodName(cfg.method), result.stats.totalSeconds()));
    return 0;
}

int cmdInfo(int argc, char** argv) {
    bool gpu = false;
    Command cmd("raysplat info SCENE", "Loads SCENE and prints what the renderer sees in it.");
    cmd.add({"--gpu", "", "also report the EGL device the voxelizer would use (not built yet)", [&](const std::string&) { gpu = true; }});
    bool help;
    std::vector<std::string> pos = cmd.parse(argc, argv, 2, help);
    if (help) return 0;
    if (pos.size() != 1) throw Error(ErrorKind::Config, "info needs exactly one SCENE (see raysplat info --help)");
    ConsoleReporter reporter(false);
    Scene s = loadScene(pos[0], reporter);

    std::map<std::string, int> kinds;
    std::vector<size_t> trisOf(s.materials.size(), 0);
    for (uint32_t m : s.triMaterial) trisOf[m]++;
    size_t emissiveTris = 0;
    for (size_t m = 0; m < s.materials.size(); ++m) {
        if (!trisOf[m]) continue;
        kinds[materialKindName(s.materials[m].kind)]++;
        if (s.materials[m].isEmissive()) emissiveTris += trisOf[m];
    }
    std::map<std::string, int> lightTypes;
    for (const PunctualLight& l : s.lights)
        lightTypes[l.type == LightType::Point ? "point" : l.type == LightType::Spot ? "spot" : "directional"]++;

    std::printf("scene       %s\n", s.path.c_str());
    std::printf("triangles   %zu in %zu primitives\n", s.triangleCount(), s.objectNames.size());
    std::string mk;
    for (auto& [k, n] : kinds) mk += fmt("%s%d %s", mk.empty() ? "" : ", ", n, k.c_str());
    std::printf("materials   %s\n", mk.empty() ? "none" : mk.c_str());
    std::string lk = fmt("%zu emissive triangles", emissiveTris);
    for (auto& [k, n] : lightTypes) lk += fmt(", %d %s", n, k.c_str());
    std::printf("lights      %s\n", lk.c_str());
    Vec3 power = s.emittedPower();
    std::printf("power       %.4g W (RGB %.4g, %.4g, %.4g)\n", luminance(power), power.x, power.y, power.z);
    Camera c = s.camera();
    std::printf("camera      '%s' at %s looking %s, yfov %.1f deg%s\n", c.name.c_str(), vec(c.position).c_str(),
                vec(c.forward).c_str(), c.yfov * 180.0 / kPi, s.cameras.empty() ? " (none in the file: framing the bounds)" : "");
    std::printf("bounds      %s to %s (m)\n", vec(s.bounds.lo).c_str(), vec(s.bounds.hi).c_str());
    if (gpu) std::printf("gpu         the GPU voxelizer is not built yet\n");
    return 0;
}

int cmdVoxelize(int argc, char** argv) {
    Command cmd("raysplat voxelize SCENE -o GRID.vdb", "Voxelizes SCENE into an occlusion grid (not built yet).");
    bool help;
    cmd.parse(argc, argv, 2, help);
    if (help) return 0;
    throw Error(ErrorKind::Config, "voxelize: not built yet");
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2 || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "help")) {
        std::fputs(kTopHelp, argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    std::string command = argv[1];
    try {
        if (command == "--version") { std::printf("raysplat %s\n", versionString()); return 0; }
        if (command == "render") return cmdRender(argc, argv);
        if (command == "info") return cmdInfo(argc, argv);
        if (command == "voxelize") return cmdVoxelize(argc, argv);
        throw Error(ErrorKind::Config, "unknown command '" + command + "' (commands: render, info, voxelize)");
    } catch (const Error& e) {
        std::fprintf(stderr, "raysplat: error: %s\n", e.what());
        return 1;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "raysplat: error: out of memory\n");
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raysplat: error: %s\n", e.what());
        return 1;
    }
}
