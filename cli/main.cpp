// The raysplat command: argument parsing, console log and progress. The only place that
// catches rs::Error: it prints "raysplat: error: …" on one line and exits with 1.
#include <signal.h>
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

#include "core/error.h"
#include "grid/gpu_context.h"
#include "grid/grid_stage.h"
#include "core/log.h"
#include "core/parallel.h"
#include "memory.h"
#include "render.h"
#include "scene/scene.h"
#include "core/stats.h"
#include "core/stop.h"

using namespace rs;

namespace {

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

// -- Console reporter: a progress bar on a TTY, plain lines otherwise, nothing with --quiet.
// Stages may nest one level: the render's passes are the outer stage, each pass's stages
// (eye pass, photons, splatting) the inner one; the bar then shows both, and only the
// outer stage prints lines.
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
        const bool nested = depth_ == 1;
        depth_ = std::min(depth_ + 1, 2);
        Progress& p = nested ? inner_ : outer_;
        p.start(stage, total, unit);
        if (nested) outer_.hasInner = true;
        if (!quiet_ && !tty_ && !nested) {
            if (total > 0) std::fprintf(stderr, "raysplat: %s: %lld %s\n", stage.c_str(), (long long)total, unit);
            else std::fprintf(stderr, "raysplat: %s\n", stage.c_str());
        }
    }
    void advance(int64_t units) override {
        std::lock_guard<std::mutex> lock(mutex_);
        Progress& p = depth_ == 2 ? inner_ : outer_;
        p.done += units;
        if (quiet_) return;
        if (!tty_) {
            if (depth_ == 1 && p.hasInner)  // a line per unit of work made of stages
                std::fprintf(stderr, "raysplat: %s: pass %lld%s done, %.1f s\n", p.stage.c_str(), (long long)p.done,
                             p.total > 0 ? fmtTotal(p.total).c_str() : "", p.timer.seconds());
            return;
        }
        double now = outer_.timer.seconds();
        if (now - lastDraw_ < 0.1 && p.done < p.total) return;
        lastDraw_ = now;
        drawBar();
    }
    void end() override {
        std::lock_guard<std::mutex> lock(mutex_);
        const bool nested = depth_ == 2;
        depth_ = std::max(depth_ - 1, 0);
        if (quiet_ || nested) return;
        clearBar();
        std::fprintf(stderr, "raysplat: %s done in %.2f s\n", outer_.stage.c_str(), outer_.timer.seconds());
    }

private:
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
    static std::string fmtTotal(int64_t total) { return "/" + std::to_string(total); }

    void drawBar() {
        const int width = 30;
        const Progress& o = outer_;
        std::string line = "\r\033[Kraysplat: " + o.stage;
        char buf[256];
        if (o.total > 0) {
            // The outer bar counts the current unit's inner progress as a fraction of one unit.
            double f = std::min(1.0, (double(o.done) + (depth_ == 2 ? inner_.fraction() : 0.0)) / double(o.total));
            int fill = int(f * width);
            double eta = f > 0.0 ? o.timer.seconds() * (1.0 - f) / f : 0.0;
            std::snprintf(buf, sizeof buf, " [%.*s%*s] %3d%% %lld/%lld %s, %.1f s left", fill,
                          "##############################", width - fill, "", int(f * 100), (long long)o.done,
                          (long long)o.total, o.unit, eta);
        } else {
            std::snprintf(buf, sizeof buf, " %lld %s, %.1f s", (long long)o.done, o.unit, o.timer.seconds());
        }
        line += buf;
        if (depth_ == 2) {
            std::snprintf(buf, sizeof buf, " · %s %3d%%", inner_.stage.c_str(), int(inner_.fraction() * 100));
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
    int depth_ = 0;
    Progress outer_, inner_;
    double lastDraw_ = -1.0;
    bool barShown_ = false;
};

// -- Arguments --------------------------------------------------------------------------------

struct Option {
    std::string name;  // "--spp"
    std::string arg;   // "N", or "" for a switch
    std::string help;
    std::function<void(const std::string&)> set;
    std::string shortName = "";  // "-o", or none
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

// "8G", "512M", "64k" or bytes → bytes (binary units).
uint64_t parseSize(const std::string& flag, const std::string& s) {
    const char unit = s.empty() ? '\0' : char(std::toupper(static_cast<unsigned char>(s.back())));
    const int shift = unit == 'K' ? 10 : unit == 'M' ? 20 : unit == 'G' ? 30 : unit == 'T' ? 40 : 0;
    const double v = parseFloat(flag, shift ? s.substr(0, s.size() - 1) : s);
    if (!(v > 0.0) || v * double(uint64_t(1) << shift) > 1e18)
        throw Error(ErrorKind::Config, flag + " " + s + " is not a size (a positive number of bytes, or with K, M, G, T)");
    return uint64_t(v * double(uint64_t(1) << shift));
}

// "a,b,c" → three numbers.
void parseTriple(const std::string& flag, const std::string& s, std::array<float, 3>& out) {
    float v[3];
    size_t start = 0;
    for (int i = 0; i < 3; ++i) {
        size_t end = i < 2 ? s.find(',', start) : s.size();
        if (end == std::string::npos) throw Error(ErrorKind::Config, flag + ": '" + s + "' is not three numbers a,b,c");
        v[i] = parseFloat(flag, s.substr(start, end - start));
        start = end + 1;
    }
    for (int i = 0; i < 3; ++i) out[i] = v[i];
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
            std::string left = (o.shortName.empty() ? "" : o.shortName + ", ") + o.name + (o.arg.empty() ? "" : " " + o.arg);
            std::printf("  %-22s %s\n", left.c_str(), o.help.c_str());
        }
        std::printf("  %-22s %s\n", "-h, --help", "show this help");
    }

private:
    const Option* find(const std::string& name) const {
        for (const Option& o : options_)
            if (o.name == name || (!o.shortName.empty() && o.shortName == name)) return &o;
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
    "  compare A.exr REF.exr     relative MSE and RMSE of A against a reference, per layer\n"
    "  voxelize SCENE -o G.vdb   voxelize the scene into an occlusion grid (OpenVDB; opens in Blender)\n"
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

std::string vec(const Vec3& v) { return fmt("(%.4g, %.4g, %.4g)", v.x + 0.f, v.y + 0.f, v.z + 0.f); }  // no "-0"

// The occlusion grid's options, shared by render and voxelize.
void addGridOptions(Command& cmd, RenderConfig& cfg) {
    cmd.add({"--grid", "N", "occlusion grid: voxels along the scene's longest axis (default 192, 1..4096)",
             [&](const std::string& v) { cfg.grid = parseNumber<int>("--grid", v); }});
    cmd.add({"--voxelizer", "NAME", "auto (GPU via EGL, else CPU with a warning; default), gpu, cpu",
             [&](const std::string& v) { cfg.voxelizer = v; }});
    cmd.add({"--cache", "DIR", "voxel cache: reuse DIR/<key>.vdb when scene and settings match, else write it",
             [&](const std::string& v) { cfg.cacheDir = v; }});
    cmd.add({"--max-memory", "SIZE", "refuse settings whose estimated memory exceeds SIZE (e.g. 8G, 512M; default: "
                                     "the memory available now)",
             [&](const std::string& v) { cfg.maxMemory = parseSize("--max-memory", v); }});
}

int cmdRender(int argc, char** argv) {
    RenderConfig cfg;
    bool quiet = false;
    Command cmd("raysplat render SCENE -o OUT.exr [options]",
                "Renders SCENE (.gltf or .glb) and writes a float OpenEXR with the beauty image and the layers\n"
                "direct, indirect, caustic, emission, albedo and normal. The default method is photon ray splatting\n"
                "(Herzog & Seidel 2007): GPU voxelization (EGL) once, then 8 passes of eye pass, occlusion tree,\n"
                "photons and splatting, averaged, with kernels shrinking from pass to pass. Direct light is sampled\n"
                "at every eye sample, as a path tracer does; '--direct photons --passes 1' is the paper's own\n"
                "estimator (4 samples a pixel, 100000 photons split 20/50/30, grid 192). Outputs are written\n"
                "atomically: a failed run leaves no file behind.");
    cmd.add({"--output", "FILE", "OpenEXR output", [&](const std::string& v) { cfg.output = v; }, "-o"});
    cmd.add({"--png", "FILE", "also write a tone-mapped sRGB PNG preview", [&](const std::string& v) { cfg.png = v; }});
    cmd.add({"--stats-json", "FILE", "write per-stage times and counts as JSON", [&](const std::string& v) { cfg.statsJson = v; }});
    cmd.add({"--method", "NAME", "splat (default: photon ray splatting with visibility), splat-novis (without), path (reference)",
             [&](const std::string& v) { cfg.method = parseMethod(v); }});
    cmd.add({"--width", "N", "image width in pixels (default 500; 0: from --height and the camera aspect)",
             [&](const std::string& v) { cfg.width = parseNumber<int>("--width", v); }});
    cmd.add({"--height", "N", "image height (default: from the width and the camera's aspect ratio)",
             [&](const std::string& v) { cfg.height = parseNumber<int>("--height", v); }});
    cmd.add({"--spp", "N", "samples per pixel and pass (default: splat 4 eye samples, path 16)",
             [&](const std::string& v) {
                 cfg.spp = parseNumber<int>("--spp", v);
                 if (cfg.spp < 1) throw Error(ErrorKind::Config, "--spp " + v + " is out of range (1..1048576)");
             }});
    cmd.add({"--direct", "NAME", "direct light: sample (default: light sampling at every eye sample), photons (the paper's)",
             [&](const std::string& v) { cfg.direct = parseDirectMethod(v); }});
    cmd.add({"--light-samples", "N", "light samples per eye sample for --direct sample (default 8)",
             [&](const std::string& v) { cfg.lightSamples = parseNumber<int>("--light-samples", v); }});
    cmd.add({"--photons", "M", "photon rays stored per pass (default 100000)",
             [&](const std::string& v) { cfg.photons = parseNumber<int64_t>("--photons", v); }});
    cmd.add({"--split", "D,I,C", "shares of direct, indirect and caustic photons (default 0,0.5,0.3; with --direct photons 0.2,0.5,0.3)",
             [&](const std::string& v) {
                 parseTriple("--split", v, cfg.split);
                 cfg.splitSet = true;
             }});
    cmd.add({"--kernel-photons", "D,I,C", "photons aimed for under one kernel, per class (default 16,32,16)",
             [&](const std::string& v) { parseTriple("--kernel-photons", v, cfg.kernelPhotons); }});
    cmd.add({"--min-radius", "D,I,C", "smallest splat radius in voxels, per class (default 1,6,1)",
             [&](const std::string& v) { parseTriple("--min-radius", v, cfg.minRadius); }});
    cmd.add({"--max-radius", "D,I,C", "largest splat radius in voxels, per class (default 16,24,16)",
             [&](const std::string& v) { parseTriple("--max-radius", v, cfg.maxRadius); }});
    cmd.add({"--max-depth", "N", "longest path, in vertices (default 32)",
             [&](const std::string& v) { cfg.maxDepth = parseNumber<int>("--max-depth", v); }});
    cmd.add({"--passes", "N", "passes to render and average (default: splat 8, each new eye samples and photons; path 1 of --spp)",
             [&](const std::string& v) {
                 cfg.passes = parseNumber<int>("--passes", v);
                 if (cfg.passes < 1) throw Error(ErrorKind::Config, "--passes " + v + " is out of range (1..1048576)");
             }});
    cmd.add({"--time-limit", "SECONDS", "render passes until the time is up (at least one), instead of --passes",
             [&](const std::string& v) { cfg.timeLimit = parseFloat("--time-limit", v); }});
    cmd.add({"--alpha", "A", "kernel shrinkage between passes, r^2 *= (i + A)/(i + 1) (default 0.667)",
             [&](const std::string& v) { cfg.alpha = parseFloat("--alpha", v); }});
    cmd.add({"--camera", "NAME", "the glTF camera to use (default: the first one)", [&](const std::string& v) { cfg.camera = v; }});
    cmd.add({"--seed", "N", "seed of every random sequence (default 0)", [&](const std::string& v) { cfg.seed = parseNumber<uint64_t>("--seed", v); }});
    cmd.add({"--threads", "N", "worker threads (default 0: all cores); the image does not depend on it",
             [&](const std::string& v) { cfg.threads = parseNumber<int>("--threads", v); }});
    cmd.add({"--exposure", "STOPS", "exposure of the PNG preview (default 0)", [&](const std::string& v) { cfg.exposure = parseFloat("--exposure", v); }});
    addGridOptions(cmd, cfg);
    cmd.add({"--vdb", "FILE", "also write the occlusion grid as OpenVDB (opens in Blender as a volume)",
             [&](const std::string& v) { cfg.vdb = v; }});
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
    cmd.add({"--gpu", "", "also report the EGL device the voxelizer would use", [&](const std::string&) { gpu = true; }});
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
    if (gpu) {
        std::string description;
        try {
            description = describeGpu();
        } catch (const Error& e) {
            description = std::string("none: ") + withFlags(e.what());
        }
        std::printf("gpu         %s\n", description.c_str());
    }
    return 0;
}

int cmdVoxelize(int argc, char** argv) {
    RenderConfig cfg;
    bool quiet = false;
    Command cmd("raysplat voxelize SCENE -o GRID.vdb [options]",
                "Voxelizes SCENE (.gltf or .glb) into the occlusion grid the splat renderer uses (six occlusion\n"
                "ratios per voxel, 4x4 sub-samples per face) and writes it as OpenVDB: grids density (fog volume),\n"
                "normal (vec3s) and occ_px, occ_nx, occ_py, occ_ny, occ_pz, occ_nz (count/16), plus metadata (dims,\n"
                "voxel size, origin, voxelizer, cache key). The file opens in Blender (Add > Volume > Import\n"
                "OpenVDB) and overlays the scene imported with Blender's glTF importer. Written atomically.");
    cmd.add({"--output", "FILE", "the .vdb to write", [&](const std::string& v) { cfg.vdb = v; }, "-o"});
    addGridOptions(cmd, cfg);
    cmd.add({"--threads", "N", "worker threads of the CPU voxelizer (default 0: all cores); the grid does not depend on it",
             [&](const std::string& v) { cfg.threads = parseNumber<int>("--threads", v); }});
    cmd.add({"--quiet", "", "no progress or messages, only errors and warnings", [&](const std::string&) { quiet = true; }});
    bool help;
    std::vector<std::string> pos = cmd.parse(argc, argv, 2, help);
    if (help) return 0;
    if (pos.size() != 1) throw Error(ErrorKind::Config, "voxelize needs exactly one SCENE (see raysplat voxelize --help)");
    if (cfg.vdb.empty()) throw Error(ErrorKind::Config, "no output file: give -o GRID.vdb");
    cfg.scene = pos[0];
    cfg.validateGrid();
    if (cfg.threads < 0 || cfg.threads > 1024)
        throw Error(ErrorKind::Config, "--threads " + std::to_string(cfg.threads) + " is out of range (0..1024)");

    ConsoleReporter reporter(quiet);
    Scene scene = loadScene(cfg.scene, reporter);
    const IVec3 dims = gridForBounds(scene.bounds, cfg.grid).dims;
    const int gridDims[3] = {dims.x, dims.y, dims.z};
    MemoryEstimate memory;
    memory.grid = estimateMemory(cfg, gridDims, 0, 0, 0, 0).grid;
    checkMemory(memory, cfg.maxMemory);
    ThreadPool pool(cfg.threads);
    Stats stats;
    OcclusionGrid grid = buildGrid(scene, cfg.gridSettings(), pool, reporter, stats);
    const GridGeometry& g = grid.geometry;
    size_t occupied = grid.occupiedCount();
    bool cacheHit = false;
    for (const auto& [name, value] : stats.counts)
        if (name == "grid_cache_hit") cacheHit = value != 0;
    reporter.info(fmt("wrote %s: %dx%dx%d voxels of %.4g m, %zu occupied (%.2f%%), %.2f s%s", cfg.vdb.c_str(), g.dims.x,
                      g.dims.y, g.dims.z, g.voxelSize, occupied,
                      100.0 * double(occupied) / double(std::max<size_t>(g.voxelCount(), 1)), stats.time("voxelize"),
                      cacheHit ? " (from the cache)" : ""));
    return 0;
}

int cmdCompare(int argc, char** argv) {
    Command cmd("raysplat compare IMAGE.exr REFERENCE.exr",
                "Compares two EXRs of the same size: relative MSE (mean over pixels and channels of\n"
                "(a - r)^2 / (r^2 + 0.01)) and RMSE, for the beauty image and each layer both files have.");
    bool help;
    std::vector<std::string> pos = cmd.parse(argc, argv, 2, help);
    if (help) return 0;
    if (pos.size() != 2) throw Error(ErrorKind::Config, "compare needs IMAGE.exr and REFERENCE.exr");
    ExrImage a = readExr(pos[0]), r = readExr(pos[1]);
    if (a.width != r.width || a.height != r.height)
        throw Error(ErrorKind::Config, fmt("%s is %dx%d but %s is %dx%d", pos[0].c_str(), a.width, a.height, pos[1].c_str(),
                                           r.width, r.height));
    std::printf("%-10s %12s %12s\n", "layer", "rel. MSE", "RMSE");
    for (std::string prefix : {"", "direct.", "indirect.", "caustic.", "emission."}) {
        if (!a.channels.count(prefix + "R") || !r.channels.count(prefix + "R")) continue;
        std::vector<Vec3> x = a.rgb(prefix), y = r.rgb(prefix);
        double mse = 0.0;
        for (size_t i = 0; i < x.size(); ++i) mse += glm::dot(x[i] - y[i], x[i] - y[i]) / 3.0;
        std::string name = prefix.empty() ? "beauty" : prefix.substr(0, prefix.size() - 1);
        std::printf("%-10s %12.6g %12.6g\n", name.c_str(), relativeMse(x, y), std::sqrt(mse / double(x.size())));
    }
    return 0;
}

// SIGINT and SIGTERM ask the render to stop (core/stop.h): it ends at the next chunk of work,
// its staged outputs are removed, and the command exits 128 + the signal. A second signal
// changes nothing: the first one's cleanup runs to its end.
extern "C" void onStopSignal(int signal) { requestStop(signal); }

void installStopHandlers() {
    struct sigaction action {};
    action.sa_handler = onStopSignal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2 || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "help")) {
        std::fputs(kTopHelp, argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    std::string command = argv[1];
    installStopHandlers();
    try {
        if (command == "--version") { std::printf("raysplat %s\n", versionString()); return 0; }
        if (command == "render") return cmdRender(argc, argv);
        if (command == "info") return cmdInfo(argc, argv);
        if (command == "voxelize") return cmdVoxelize(argc, argv);
        if (command == "compare") return cmdCompare(argc, argv);
        throw Error(ErrorKind::Config, "unknown command '" + command + "' (commands: render, info, voxelize, compare)");
    } catch (const Error& e) {
        if (e.kind() == ErrorKind::Interrupted) {
            std::fprintf(stderr, "raysplat: %s: stopped, no output written\n", e.what());
            return 128 + stopSignal();
        }
        std::fprintf(stderr, "raysplat: error: %s\n", withFlags(e.what()).c_str());
        return 1;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "raysplat: error: out of memory\n");
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "raysplat: error: %s\n", e.what());
        return 1;
    }
}
