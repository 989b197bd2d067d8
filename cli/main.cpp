// The raysplat command: argument parsing, console log and progress. The only place that
// catches rs::Error: it prints "raysplat: error: …" on one line and exits with 1.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdarg>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/error.h"
#include "grid/gpu_context.h"
#include "grid/grid_stage.h"
#include "core/log.h"
#include "core/parallel.h"
#include "memory.h"
#include "mpi_ranks.h"
#include "options.h"
#include "poses.h"
#include "reporters.h"
#include "render.h"
#include "walkthrough.h"
#include "scene/scene.h"
#include "core/stats.h"
#include "core/simd.h"
#include "core/stop.h"

using namespace rs;
using rs::cli::Command;
using rs::cli::withFlags;

namespace {

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

// The render's defaults, for programs that set some options and want to show the rest (the
// Blender add-on): read from RenderConfig, so that they are written once.
std::string defaultsJson() {
    RenderConfig splat, path;
    path.method = Method::Path;
    return fmt("{\"method\": \"%s\", \"width\": %d, \"passes\": {\"splat\": %d, \"path\": %d}, "
               "\"spp\": {\"splat\": %d, \"path\": %d}, \"direct_spp\": %d, \"light_samples\": %d, "
               "\"photons\": %lld, \"grid\": %d, \"threads\": %d, \"seed\": %llu, \"time_limit\": %g}\n",
               methodName(splat.method), splat.width, splat.passCount(), path.passCount(), splat.samplesPerPixel(),
               path.samplesPerPixel(), splat.directSpp, splat.lightSamples, (long long)splat.photons, splat.grid,
               splat.threads, (unsigned long long)splat.seed, splat.timeLimit);
}

// Under mpirun every rank renders its part (lib/ranks.h); rank 0 alone reports and writes.
int cmdRender(int argc, char** argv, Ranks& ranks) {
    cli::Arguments args = cli::parseRender(argc, argv);
    if (args.help) return 0;
    if (args.defaults) {
        if (ranks.rank() == 0) std::fputs(defaultsJson().c_str(), stdout);
        return 0;
    }
    RenderConfig& cfg = args.cfg;
    const bool root = ranks.rank() == 0;
    if (!root) cfg.vdb.clear();
    std::unique_ptr<Reporter> console = cli::makeReporter(args.quiet, args.json);
    Reporter& reporter = root ? *console : silentReporter();
    if (cfg.walkthrough()) {
        Timer run;
        const int rendered = Walkthrough(cfg, reporter, ranks).run();
        reporter.info(fmt("%d of %d frames rendered, %.2f s", rendered, cfg.frameCount(), run.seconds()));
        if (root) cli::reportDone(args.json, cfg.output, run.seconds());
        return 0;
    }
    Timer load;
    Scene scene = loadScene(cfg.scene, reporter, cfg.threads);
    double loadSeconds = load.seconds();
    RenderResult result = render(scene, cfg, reporter, ranks);
    result.stats.seconds.insert(result.stats.seconds.begin(), {"load", loadSeconds});
    if (root) writeOutputs(result, cfg);
    // Rank 0 wrote its outputs: the others learn here whether that failed.
    if (ranks.size() > 1 && ranks.agree(true, false).failedRank >= 0) throw Error(ErrorKind::OtherRank, "rank 0 failed");
    std::string ranksNote = ranks.size() > 1 ? fmt(", %d ranks", ranks.size()) : "";
    reporter.info(fmt("wrote %s (%dx%d, %s, %.2f s%s)", cfg.output.c_str(), result.film.width, result.film.height,
                      methodName(cfg.method), result.stats.totalSeconds(), ranksNote.c_str()));
    if (root) cli::reportDone(args.json, cfg.output, result.stats.totalSeconds());
    return 0;
}

// Each animation: its name, the nodes and paths it moves, its time range and frames at `fps`.
void printAnimations(const SceneAnimation& a, float fps) {
    if (!(fps > 0.f && fps <= 1000.f)) throw Error(ErrorKind::Config, fmt("--fps %g is out of range (0.001..1000)", fps));
    if (!a.animated()) return;
    std::printf("animations  %zu, frames at %g fps%s\n", a.animations.size(), fps,
                a.unsupported.empty() ? "" : (" (" + a.unsupported + " not animated: rest pose)").c_str());
    for (size_t i = 0; i < a.animations.size(); ++i) {
        const Animation& anim = a.animations[i];
        // Paths by node, in the order the channels name them.
        std::vector<std::pair<int, std::string>> moved;
        for (const AnimationChannel& c : anim.channels) {
            auto it = std::find_if(moved.begin(), moved.end(), [&](const auto& m) { return m.first == c.node; });
            if (it == moved.end()) moved.push_back({c.node, animatedPathName(c.path)});
            else it->second += std::string(", ") + animatedPathName(c.path);
        }
        std::string nodes;
        for (const auto& [node, paths] : moved) nodes += (nodes.empty() ? "" : "; ") + a.nodeNames[node] + " " + paths;
        std::printf("  %zu '%s': %.4g to %.4g s, frames %ld-%ld: %s\n", i, anim.name.c_str(), anim.start, anim.end,
                    std::lround(anim.start * fps), std::lround(anim.end * fps), nodes.empty() ? "no channels" : nodes.c_str());
    }
}

int cmdInfo(int argc, char** argv) {
    bool gpu = false;
    Command cmd("raysplat info SCENE", "Loads SCENE and prints what the renderer sees in it.");
    cmd.add({"--gpu", "", "also report the EGL device the GPU voxelizer would use (--voxelizer auto uses it when it is hardware)", [&](const std::string&) { gpu = true; }});
    RenderConfig frames;  // --frames and what goes with it
    float& fps = frames.fps;
    cmd.add({"--fps", "F", "frames a second the animations' frames are counted at (default " + numberText(fps) + ")",
             [&](const std::string& v) { fps = cli::parseFloat("--fps", v); }});
    cmd.add({"--frames", "A-B",
             "instead of the summary, print each frame's pose as one JSON object a line: {\"frame\", \"time\" (s), \"camera\": "
             "{\"name\", \"position\", \"forward\", \"up\", \"right\", \"yfov\" (radians)}, \"nodes\": [{\"index\", \"node\", "
             "\"world\": 16 numbers, column-major}], \"objects\": [{\"name\", \"lo\", \"hi\"}] (each primitive's world bounds)}, in glTF's axes, as render --frames places them",
             [&](const std::string& v) { cli::parseFrames(v, frames); }});
    cmd.add({"--frame-step", "N", "with --frames, every Nth frame", [&](const std::string& v) { frames.frameStep = cli::parseNumber<int>("--frame-step", v); }});
    cmd.add({"--animation", "NAME", "with --frames, as render's --animation", [&](const std::string& v) { frames.animation = v; }});
    cmd.add({"--camera", "CAMERA", "with --frames, the camera to pose, as render's --camera", [&](const std::string& v) { frames.camera = v; }});
    bool help;
    std::vector<std::string> pos = cmd.parse(argc, argv, 2, help);
    if (help) return 0;
    if (pos.size() != 1) throw Error(ErrorKind::Config, "info needs exactly one SCENE (see raysplat info --help)");
    frames.validateFrames();
    std::unique_ptr<Reporter> reporter = cli::makeReporter(false, false);
    if (frames.walkthrough()) {
        SceneFile file(pos[0], *reporter);
        cli::printPoses(file, frames);
        return 0;
    }
    Scene s = loadScene(pos[0], *reporter);

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
    if (!s.portals.empty()) std::printf("portals     %zu triangles (sun and sky photons enter through them)\n", s.portals.size() / 3);
    Vec3 power = s.emittedPower();
    std::printf("power       %.4g W (RGB %.4g, %.4g, %.4g)\n", luminance(power), power.x, power.y, power.z);
    // Every camera, by the index, name and node that --camera takes; the first is the default.
    auto describe = [&](const Camera& c) {
        const std::string view = c.projection == Projection::Orthographic
                                     ? fmt("orthographic, %.4g m high", 2.0 * c.ymag)
                                     : fmt("perspective, yfov %.1f deg", c.yfov * 180.0 / kPi);
        return fmt("'%s'%s, %s, at %s looking %s", c.name.c_str(), c.node.empty() ? "" : fmt(" (node '%s')", c.node.c_str()).c_str(),
                   view.c_str(), vec(c.position).c_str(), vec(c.forward).c_str());
    };
    if (s.cameras.empty()) std::printf("camera      %s (none in the file: framing the bounds)\n", describe(s.camera()).c_str());
    for (size_t i = 0; i < s.cameras.size(); ++i)
        std::printf("camera %-4zu %s%s\n", i, describe(s.cameras[i]).c_str(), i == 0 ? " (the default)" : "");
    std::printf("bounds      %s to %s (m)\n", vec(s.bounds.lo).c_str(), vec(s.bounds.hi).c_str());
    printAnimations(s.animation, fps);
    checkSimdEnvironment();
    std::printf("simd        %s: the occlusion tree's traversal runs %d lanes wide\n", isaName(traversalIsa()), int(traversalIsa()));
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
    cli::Arguments args = cli::parseVoxelize(argc, argv);
    if (args.help) return 0;
    const RenderConfig& cfg = args.cfg;
    std::unique_ptr<Reporter> console = cli::makeReporter(args.quiet, args.json);
    Reporter& reporter = *console;
    Scene scene = loadScene(cfg.scene, reporter, cfg.threads);
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
    cli::reportDone(args.json, cfg.vdb, stats.time("voxelize"));
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

// One line for an error, from one rank: a failed rank tells the others (lib/ranks.h), and
// the lowest failed rank speaks. OtherRank errors were said by another rank.
int reportError(Ranks& ranks, const Error* error, const std::string& message) {
    if (error && error->kind() == ErrorKind::OtherRank) return 1;
    if (ranks.size() > 1 && ranks.agree(false, false).failedRank != ranks.rank()) return 1;
    if (error && error->kind() == ErrorKind::Interrupted) {
        std::fprintf(stderr, "raysplat: %s: stopped, no output written\n", message.c_str());
        return 128 + stopSignal();
    }
    std::fprintf(stderr, "raysplat: error: %s\n", message.c_str());
    return 1;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2 || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "help")) {
        std::fputs(kTopHelp, argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    std::string command = argv[1];
    installStopHandlers();
    std::unique_ptr<Ranks> mpi;
    try {
        mpi = cli::joinMpiJob(&argc, &argv);
    } catch (const Error& e) {
        return reportError(singleProcess(), &e, withFlags(e.what()));
    }
    // Only a render is divided between ranks; under mpirun the other commands run on rank 0.
    const bool distributed = mpi && command == "render";
    if (mpi && !distributed && mpi->rank() != 0) return 0;
    Ranks& ranks = distributed ? *mpi : singleProcess();
    try {
        if (command == "--version") { std::printf("raysplat %s\n", versionString()); return 0; }
        if (command == "render") return cmdRender(argc, argv, ranks);
        if (command == "info") return cmdInfo(argc, argv);
        if (command == "voxelize") return cmdVoxelize(argc, argv);
        if (command == "compare") return cmdCompare(argc, argv);
        throw Error(ErrorKind::Config, "unknown command '" + command + "' (commands: render, info, voxelize, compare)");
    } catch (const Error& e) {
        return reportError(ranks, &e, e.kind() == ErrorKind::Interrupted ? e.what() : withFlags(e.what()));
    } catch (const std::bad_alloc&) {
        return reportError(ranks, nullptr, "out of memory");
    } catch (const std::exception& e) {
        return reportError(ranks, nullptr, e.what());
    }
}
