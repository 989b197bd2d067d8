#include "options.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace rs::cli {

float parseFloat(const std::string& flag, const std::string& s) {
    char* end = nullptr;
    float v = std::strtof(s.c_str(), &end);
    if (s.empty() || *end != '\0' || !std::isfinite(v)) throw Error(ErrorKind::Config, flag + ": '" + s + "' is not a valid number");
    return v;
}

double parseCountValue(const std::string& flag, const std::string& s, double most) {
    const char unit = s.empty() ? '\0' : s.back();
    const double scale = unit == 'k' || unit == 'K' ? 1e3 : unit == 'M' ? 1e6 : unit == 'G' ? 1e9 : 1.0;
    const std::string number = scale != 1.0 ? s.substr(0, s.size() - 1) : s;
    char* end = nullptr;
    const double v = std::strtod(number.c_str(), &end) * scale;
    if (number.empty() || *end != '\0' || !std::isfinite(v) || v < 0.0 || v != std::floor(v) || v > most)
        throw Error(ErrorKind::Config, flag + ": '" + s + "' is not a count (digits, or a whole number such as 1e6, 2M, 500k)");
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

std::vector<std::string> Command::parse(int argc, char** argv, int first, bool& helpShown) {
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


void Command::printHelp() const {
    std::printf("usage: %s\n\n%s\n\noptions:\n", usage_.c_str(), summary_.c_str());
    for (const Option& o : options_) {
        std::string left = (o.shortName.empty() ? "" : o.shortName + ", ") + o.name + (o.arg.empty() ? "" : " " + o.arg);
        std::printf("  %-22s %s\n", left.c_str(), o.help.c_str());
    }
    std::printf("  %-22s %s\n", "-h, --help", "show this help");
}


const Option* Command::find(const std::string& name) const {
    for (const Option& o : options_)
        if (o.name == name || (!o.shortName.empty() && o.shortName == name)) return &o;
    return nullptr;
}

void parseFrames(const std::string& v, RenderConfig& cfg) {
    const size_t dash = v.find('-', 1);
    if (v.empty() || v[0] == '-' || (dash != std::string::npos && dash + 1 < v.size() && v[dash + 1] == '-'))
        throw Error(ErrorKind::Config, "--frames " + v + ": frames are not negative");
    cfg.firstFrame = parseNumber<int>("--frames", v.substr(0, dash));
    cfg.lastFrame = dash == std::string::npos ? cfg.firstFrame : parseNumber<int>("--frames", v.substr(dash + 1));
}

namespace {

// The occlusion grid's options, shared by render and voxelize.
void addGridOptions(Command& cmd, RenderConfig& cfg) {
    cmd.add({"--grid", "N", "occlusion grid: voxels along the scene's longest axis (default " + std::to_string(RenderConfig{}.grid) +
                                ", 1.." + std::to_string(kMaxGridResolution) + ")",
             [&](const std::string& v) { cfg.grid = parseNumber<int>("--grid", v); }});
    cmd.add({"--voxelizer", "NAME", "auto (default: GPU on a hardware EGL device, else the CPU voxelizer, which gives the same grid faster than a software one), gpu (EGL, llvmpipe included), cpu",
             [&](const std::string& v) { cfg.voxelizer = v; }});
    cmd.add({"--cache", "DIR", "voxel cache: reuse DIR/<key>.vdb when scene and settings match, else write it",
             [&](const std::string& v) { cfg.cacheDir = v; }});
    cmd.add({"--max-memory", "SIZE", "refuse settings whose estimated memory exceeds SIZE (e.g. 8G, 512M; default: "
                                     "the memory available now)",
             [&](const std::string& v) { cfg.maxMemory = parseSize("--max-memory", v); }});
}

void addQuietOption(Command& cmd, Arguments& args) {
    cmd.add({"--quiet", "", "no progress or messages, only errors and warnings", [&](const std::string&) { args.quiet = true; }});
    cmd.add({"--progress", "FORMAT",
             "text (default: a bar on a terminal, else lines), json (one JSON object a line on stderr: "
             "{\"event\": \"begin\"|\"progress\"|\"end\"|\"info\"|\"warning\"|\"frame\"|\"done\", ...}, for programs; "
             "with --frames, the events of a frame carry \"frame\": N; "
             "an error stays the one line 'raysplat: error: ...')",
             [&](const std::string& v) {
                 if (v != "text" && v != "json") throw Error(ErrorKind::Config, "--progress " + v + ": unknown format (text, json)");
                 args.json = v == "json";
             }});
}

// "20/50/30": a photon split in whole per cents.
std::string splitPercent(const ClassTriple& split) {
    const float sum = split[0] + split[1] + split[2];
    std::string out;
    for (int c = 0; c < 3; ++c) out += (c ? "/" : "") + std::to_string(int(std::lround(100.f * split[c] / sum)));
    return out;
}

// The defaults the help states, from RenderConfig: the splat's, the path tracer's and the
// paper's estimator's.
struct RenderDefaults {
    RenderConfig splat, path, paper;
    RenderDefaults() {
        path.method = Method::Path;
        paper.direct = DirectMethod::Photons;
    }
};

// The outputs, the camera and the image size.
void addOutputOptions(Command& cmd, RenderConfig& cfg, const RenderDefaults& d) {
    cmd.add({"--output", "FILE", "OpenEXR output", [&](const std::string& v) { cfg.output = v; }, "-o"});
    cmd.add({"--png", "FILE", "also write a tone-mapped sRGB PNG preview", [&](const std::string& v) { cfg.png = v; }});
    cmd.add({"--stats-json", "FILE", "write per-stage times and counts as JSON", [&](const std::string& v) { cfg.statsJson = v; }});
    cmd.add({"--blender-layer", "NAME",
             "name the EXR's channels as Blender's multilayer EXR of view layer NAME: NAME.Combined.RGBA, NAME.Direct.RGB, "
             "... NAME.Albedo.RGB, NAME.Normal.XYZ (Blender's axes), which Blender opens as passes",
             [&](const std::string& v) { cfg.blenderLayer = v; }});
    cmd.add({"--width", "N", "image width in pixels (default " + std::to_string(d.splat.width) + "; 0: from --height and the camera aspect)",
             [&](const std::string& v) { cfg.width = parseNumber<int>("--width", v); }});
    cmd.add({"--height", "N", "image height (default: from the width and the camera's aspect ratio)",
             [&](const std::string& v) { cfg.height = parseNumber<int>("--height", v); }});
    cmd.add({"--camera", "CAMERA", "the glTF camera to use: its name, its node's name or its index in the list raysplat info prints (default: the first one)",
             [&](const std::string& v) { cfg.camera = v; }});
    cmd.add({"--exposure", "STOPS", "exposure of the PNG preview (default " + numberText(d.splat.exposure) + ")", [&](const std::string& v) { cfg.exposure = parseFloat("--exposure", v); }});
}

// A walkthrough's frames.
void addFrameOptions(Command& cmd, RenderConfig& cfg, const RenderDefaults& d) {
    cmd.add({"--frames", "A-B",
             "render frames A to B (inclusive; or one frame N) of the file's animations, frame n at time n / fps, each "
             "written when it is done: '#' in -o, --png and --stats-json is the frame number, zero-padded to as many "
             "digits as there are '#' (walk_####.exr); with several frames and no '#', _NNNN goes before the extension",
             [&](const std::string& v) { parseFrames(v, cfg); }});
    cmd.add({"--frame-step", "N", "with --frames, render every Nth frame: A, A+N, A+2N … up to B (default 1)",
             [&](const std::string& v) { cfg.frameStep = parseNumber<int>("--frame-step", v); }});
    cmd.add({"--fps", "F", "frames a second of --frames (default " + numberText(d.splat.fps) + ", as Blender's)",
             [&](const std::string& v) { cfg.fps = parseFloat("--fps", v); }});
    cmd.add({"--animation", "NAME", "with --frames, play only the animation of this name or index (default: all of them together)",
             [&](const std::string& v) { cfg.animation = v; }});
    cmd.add({"--skip-existing", "", "with --frames, skip the frames whose outputs all exist (continue a stopped run)",
             [&](const std::string&) { cfg.skipExisting = true; }});
}

// The method, its samples and passes.
void addSamplingOptions(Command& cmd, RenderConfig& cfg, const RenderDefaults& d) {
    cmd.add({"--method", "NAME", "splat (default: photon ray splatting with visibility), splat-novis (without), path (reference)",
             [&](const std::string& v) { cfg.method = parseMethod(v); }});
    cmd.add({"--spp", "N", "samples per pixel and pass (default: splat " + std::to_string(d.splat.samplesPerPixel()) +
                               " eye samples, path " + std::to_string(d.path.samplesPerPixel()) + "; 0: the method's)",
             [&](const std::string& v) { cfg.spp = parseCount<int>("--spp", v); }});
    cmd.add({"--direct", "NAME", "direct light: sample (default: light sampling at every eye sample), photons (the paper's)",
             [&](const std::string& v) { cfg.direct = parseDirectMethod(v); }});
    cmd.add({"--visibility", "NAME",
             "which eye samples a photon reaches: rays (each sample's ray to the photon's origin, the kernel's coverage "
             "measured), mask (the paper's occlusion mask, then those rays); default auto: mask with --direct photons, else rays",
             [&](const std::string& v) { cfg.visibility = parseVisibility(v); }});
    cmd.add({"--coverage-probes", "N",
             "with --visibility rays, probe rays a photon measuring its kernel's coverage (default " +
                 std::to_string(d.splat.coverageProbes) + ", 0.." + std::to_string(CoverageSettings::kMaxProbes) + "; 0: no correction)",
             [&](const std::string& v) { cfg.coverageProbes = parseNumber<int>("--coverage-probes", v); }});
    cmd.add({"--coverage-at", "WHERE",
             "where the kernels' coverage corrects their loss at edges and corners: samples (each sample by the share of "
             "its own kernel that arrives, where a kernel lands on one plane; elsewhere the photon) or photons (each "
             "photon's flux by the share of its kernel that arrives); default samples",
             [&](const std::string& v) { cfg.coverageAtSamples = parseCoverageAt(v); }});
    cmd.add({"--min-coverage", "C",
             "the least share of a kernel that a photon's flux or a sample's light is divided by: fewer fireflies on thin "
             "parts, for a measured bias under 0.5 % of the indirect light "
             "(default " + numberText(d.splat.minCoverage) + ", 0..1; 0: none)",
             [&](const std::string& v) { cfg.minCoverage = parseFloat("--min-coverage", v); }});
    cmd.add({"--receiver-spacing", "F",
             "with --visibility rays, indirect photons land on receivers F times the smallest indirect kernel radius "
             "apart (over the root of the pass's photon rounds), and every eye sample takes the mean of those near it "
             "on its surface (default " +
                 numberText(d.splat.receiverSpacing) + ", 0..4; 0: on every eye sample)",
             [&](const std::string& v) { cfg.receiverSpacing = parseFloat("--receiver-spacing", v); }});
    cmd.add({"--direct-spp", "N",
             "with --direct sample, camera samples a pixel and pass of the direct film: emission, direct light, albedo "
             "and normal, apart from the photons' receivers (default " + std::to_string(d.splat.directSpp) +
                 "; 0: at the receivers); after the first pass, pixels whose film it found far noisier than the "
                 "image's (the edges of objects and hard shadows) take up to 8 times as many",
             [&](const std::string& v) { cfg.directSpp = parseCount<int>("--direct-spp", v); }});
    cmd.add({"--light-samples", "N", "light samples per direct film sample (or eye sample, with --direct-spp 0) for --direct sample (default " +
                 std::to_string(d.splat.lightSamples) + ")",
             [&](const std::string& v) { cfg.lightSamples = parseNumber<int>("--light-samples", v); }});
    cmd.add({"--passes", "N", "passes to render and average (default: splat " + std::to_string(d.splat.passCount()) +
                                  ", each new eye samples and photons; path " + std::to_string(d.path.passCount()) +
                                  " of --spp; 0: the method's)",
             [&](const std::string& v) { cfg.passes = parseCount<int>("--passes", v); }});
    cmd.add({"--time-limit", "SECONDS", "render passes until the time is up (at least one, counted from the first pass: loading and the grid come before it), instead of --passes; the first pass takes fewer film samples a pixel (and then fewer eye samples) where its eye pass would not fit half the time; with --frames, each frame's time",
             [&](const std::string& v) { cfg.timeLimit = parseFloat("--time-limit", v); }});
    cmd.add({"--film-passes", "N",
             "after the passes, N passes of the direct film alone: its camera samples for direct light, emission, albedo and "
             "normal, no photons (default 0); with --time-limit the time left after the last whole pass goes to them by itself",
             [&](const std::string& v) { cfg.filmPasses = parseCount<int>("--film-passes", v); }});
    cmd.add({"--seed", "N", "seed of every random sequence (default " + std::to_string(d.splat.seed) + ")", [&](const std::string& v) { cfg.seed = parseNumber<uint64_t>("--seed", v); }});
    cmd.add({"--threads", "N", "worker threads (default 0: every core this process may run on); the image does not depend on it",
             [&](const std::string& v) { cfg.threads = parseNumber<int>("--threads", v); }});
    cmd.add({"--photon", "PASS:INDEX",
             "replay one photon ray (debugging): the image is the splat of ray INDEX of pass PASS alone, and its record "
             "(class, ends, flux, radius, reach, coverage, eye samples reached) is printed; with the render's --seed and "
             "--passes (which set the kernel scale), the same ray as in the full render",
             [&](const std::string& v) {
                 const size_t colon = v.find(':');
                 if (colon == std::string::npos) throw Error(ErrorKind::Config, "--photon " + v + ": not PASS:INDEX");
                 cfg.replayPass = parseNumber<int>("--photon", v.substr(0, colon));
                 cfg.replayIndex = parseCount<int64_t>("--photon", v.substr(colon + 1));
                 if (cfg.replayPass < 0) throw Error(ErrorKind::Config, "--photon " + v + ": the pass is negative");
             }});
}

// The photons and their kernels.
void addPhotonOptions(Command& cmd, RenderConfig& cfg, const RenderDefaults& d) {
    cmd.add({"--photons", "M", "photon rays stored per pass, or per photon round (default " + std::to_string(d.splat.photons) + "; also 1e6, 2M, 500k)",
             [&](const std::string& v) { cfg.photons = parseCount<int64_t>("--photons", v); }});
    cmd.add({"--photon-rounds", "N",
             "photon rounds a pass, each --photons more photons splatted on the pass's eye samples: auto (default: 1, but "
             "with --time-limit the first pass weighs the noise and time of its photons against those of its eye pass and "
             "direct film, and chooses the rounds of the others, reported as photon_rounds) or a number in 1.." +
                 std::to_string(RenderConfig::kMaxPhotonRounds),
             [&](const std::string& v) { cfg.photonRounds = v == "auto" ? 0 : parseNumber<int>("--photon-rounds", v); }});
    cmd.add({"--split", "D,I,C", "shares of direct, indirect and caustic photons (default " + tripleText(d.splat.photonSplit()) +
                                     "; with --direct photons " + tripleText(d.paper.photonSplit()) + ")",
             [&](const std::string& v) {
                 parseTriple("--split", v, cfg.split);
                 cfg.splitSet = true;
             }});
    cmd.add({"--kernel-photons", "D,I,C", "photons aimed for under one kernel, per class (default " + tripleText(d.splat.kernelPhotons) + ")",
             [&](const std::string& v) { parseTriple("--kernel-photons", v, cfg.kernelPhotons); }});
    cmd.add({"--min-radius", "D,I,C", "smallest splat radius in voxels, per class (default " + tripleText(d.splat.minRadius) + ")",
             [&](const std::string& v) { parseTriple("--min-radius", v, cfg.minRadius); }});
    cmd.add({"--max-radius", "D,I,C", "largest splat radius in voxels, per class (default " + tripleText(d.splat.maxRadius) + ")",
             [&](const std::string& v) { parseTriple("--max-radius", v, cfg.maxRadius); }});
    cmd.add({"--max-depth", "N", "longest path, in vertices (default " + std::to_string(d.splat.maxDepth) + ")",
             [&](const std::string& v) { cfg.maxDepth = parseNumber<int>("--max-depth", v); }});
    cmd.add({"--kernel-scale", "S",
             "scale of the indirect photons' kernels (after --min-radius/--max-radius): auto (default: with --method splat, "
             "--direct sample and more than one pass or a time limit, the first pass measures the kernels' blur and noise "
             "and chooses it in 0.25..1.46, reported as kernel_scale; else 1) or a number in 0.05..4",
             [&](const std::string& v) { cfg.kernelScale = v == "auto" ? 0.f : parseFloat("--kernel-scale", v); }});
    cmd.add({"--alpha", "A", "kernel shrinkage between passes, r^2 *= (i + A)/(i + 1) (default " + numberText(d.splat.alpha) + ")",
             [&](const std::string& v) { cfg.alpha = parseFloat("--alpha", v); }});
}

// The sky.
void addSkyOptions(Command& cmd, RenderConfig& cfg, const RenderDefaults& d) {
    cmd.add({"--env", "FILE",
             "environment light: an equirectangular OpenEXR or Radiance .hdr, oriented as Blender's world (its centre column along +X, "
             "its top row up), seen through openings, sampled for direct light and sending photons",
             [&](const std::string& v) { cfg.env = v; }});
    cmd.add({"--env-strength", "S", "multiplies the --env image (default " + numberText(d.splat.envStrength) + ")",
             [&](const std::string& v) { cfg.envStrength = parseFloat("--env-strength", v); }});
    cmd.add({"--env-rotation", "DEG", "turns the --env image about the up axis as Blender's Mapping node Z rotation in the world shader does (default " +
                                          numberText(d.splat.envRotation) + ")",
             [&](const std::string& v) { cfg.envRotation = parseFloat("--env-rotation", v); }});
    cmd.add({"--sky", "R,G,B", "a uniform sky of this radiance, W/(m^2 sr) (one number: grey; default none)",
             [&](const std::string& v) {
                 ClassTriple c;
                 if (v.find(',') == std::string::npos) {
                     const float g = parseFloat("--sky", v);
                     c = {g, g, g};
                 } else {
                     parseTriple("--sky", v, c);
                 }
                 cfg.sky = Vec3(c[0], c[1], c[2]);
             }});
}

}  // namespace

Arguments parseRender(int argc, char** argv) {
    Arguments args;
    RenderConfig& cfg = args.cfg;
    const RenderDefaults d;
    Command cmd("raysplat render SCENE -o OUT.exr [options]",
                "Renders SCENE (.gltf or .glb) and writes a float OpenEXR with the beauty image and the layers\n"
                "direct, indirect, caustic, emission, albedo and normal. The default method is photon ray splatting\n"
                "(Herzog & Seidel 2007): " + std::to_string(d.splat.passCount()) + " passes of eye pass, tree of eye samples, photons and splatting, averaged,\n"
                "with kernels shrinking from pass to pass. Direct light and emission are sampled in a film of their\n"
                "own camera samples, as a path tracer does, and a photon reaches the eye samples that see its\n"
                "origin, its kernel's light kept whole past edges and corners. '--direct photons --passes 1' is\n"
                "the paper's own estimator (" + std::to_string(d.paper.samplesPerPixel()) + " samples a pixel, " + std::to_string(d.paper.photons) +
                " photons split " + splitPercent(d.paper.photonSplit()) + ", GPU voxelization\n"
                "into an occlusion mask of grid " + std::to_string(d.paper.grid) + ", no coverage correction). Outputs are written atomically: a\n"
                "failed run leaves no file behind. Under mpirun (a build with Open MPI) the passes, or with fewer\n"
                "passes than ranks each pass's photons, are divided between the ranks: the same image. Scenes may\n"
                "be lit by a sky (--env, --sky, or the glTF scene's extras raysplat_sky / raysplat_env); nodes whose\n"
                "extras set raysplat_portal are light portals (windows): the sun's and the sky's photons enter\n"
                "through them. glTF alphaMode MASK and BLEND cut surfaces everywhere, the voxel grid included.");
    addOutputOptions(cmd, cfg, d);
    addFrameOptions(cmd, cfg, d);
    addSamplingOptions(cmd, cfg, d);
    addPhotonOptions(cmd, cfg, d);
    addSkyOptions(cmd, cfg, d);
    addGridOptions(cmd, cfg);
    cmd.add({"--vdb", "FILE", "also write the occlusion grid as OpenVDB (opens in Blender as a volume)",
             [&](const std::string& v) { cfg.vdb = v; }});
    addQuietOption(cmd, args);
    cmd.add({"--defaults", "", "print the defaults of the settings above as one JSON object, and exit",
             [&](const std::string&) { args.defaults = true; }});
    std::vector<std::string> pos = cmd.parse(argc, argv, 2, args.help);
    if (args.help || args.defaults) return args;
    if (pos.size() != 1) throw Error(ErrorKind::Config, "render needs exactly one SCENE (see raysplat render --help)");
    cfg.scene = pos[0];
    cfg.validate();
    return args;
}

Arguments parseVoxelize(int argc, char** argv) {
    Arguments args;
    RenderConfig& cfg = args.cfg;
    Command cmd("raysplat voxelize SCENE -o GRID.vdb [options]",
                "Voxelizes SCENE (.gltf or .glb) into the occlusion grid the splat renderer uses (six occlusion\n"
                "ratios per voxel, 4x4 sub-samples per face) and writes it as OpenVDB: grids density (fog volume),\n"
                "normal (vec3s) and occ_px, occ_nx, occ_py, occ_ny, occ_pz, occ_nz (count/16), plus metadata (dims,\n"
                "voxel size, origin, voxelizer, cache key). The file opens in Blender (Add > Volume > Import\n"
                "OpenVDB) and overlays the scene imported with Blender's glTF importer. Written atomically.");
    cmd.add({"--output", "FILE", "the .vdb to write", [&](const std::string& v) { cfg.vdb = v; }, "-o"});
    addGridOptions(cmd, cfg);
    cmd.add({"--threads", "N", "worker threads of the CPU voxelizer (default 0: every core this process may run on); the grid does not depend on it",
             [&](const std::string& v) { cfg.threads = parseNumber<int>("--threads", v); }});
    addQuietOption(cmd, args);
    std::vector<std::string> pos = cmd.parse(argc, argv, 2, args.help);
    if (args.help) return args;
    if (pos.size() != 1) throw Error(ErrorKind::Config, "voxelize needs exactly one SCENE (see raysplat voxelize --help)");
    if (cfg.vdb.empty()) throw Error(ErrorKind::Config, "no output file: give -o GRID.vdb");
    cfg.scene = pos[0];
    cfg.validateGrid();
    if (cfg.threads < 0 || cfg.threads > 1024)
        throw Error(ErrorKind::Config, "--threads " + std::to_string(cfg.threads) + " is out of range (0..1024)");
    return args;
}

}  // namespace rs::cli
