// RenderConfig: every setting of a render in one aggregate with defaults; the CLI fills it,
// validate() refuses absurd values with a one-line Error(Config), and render() builds each
// stage's settings from it. Every setting that changes the image is written to the EXR
// header. Messages name a setting in backticks (`spp`), not as any command line spells it.
#pragma once

#include <string>

#include "grid/grid_stage.h"
#include "output/image_io.h"
#include "path/path.h"
#include "scene/environment.h"
#include "splat/coverage.h"
#include "splat/eye.h"
#include "splat/irradiance.h"
#include "splat/photons.h"

namespace rs {

// splat: photon ray splatting with visibility (the paper); splat-novis: the same without the
// occlusion mask (V ≡ 1, the paper's Fig. 4b); path: the reference path tracer.
enum class Method { Splat, SplatNoVis, Path };
const char* methodName(Method m);
Method parseMethod(const std::string& name);  // throws Error(Config)

// Direct light of the splat methods: sample (light sampling at every eye sample, as the
// path tracer's next-event estimation does) or photons (the paper's estimator: direct
// photons splatted like the others).
enum class DirectMethod { Sample, Photons };
const char* directMethodName(DirectMethod d);
DirectMethod parseDirectMethod(const std::string& name);  // throws Error(Config)

// How the splat decides which eye samples a photon ray's light reaches (docs/design.md §8):
// mask (the paper's occlusion mask over the voxel grid, then the receiver rules) or rays (the
// receiver rules alone: each sample's own ray to the photon's origin, and the kernel's lost
// share given back by its measured coverage). auto: mask for the paper's estimator (direct
// photons), rays otherwise.
enum class Visibility { Auto, Mask, Rays };
const char* visibilityName(Visibility v);
Visibility parseVisibility(const std::string& name);  // throws Error(Config)
bool parseCoverageAt(const std::string& name);       // samples: true, photons: false; throws Error(Config)

// A per-class triple as "a,b,c", each number in its shortest form (%g): the EXR header's
// settings and --help's defaults.
std::string tripleText(const ClassTriple& v);
std::string numberText(float v);  // %g

constexpr int kMaxImageSide = 16384;  // pixels, either side of the image

struct RenderConfig {
    std::string scene;
    std::string output;     // .exr
    std::string png;        // optional preview
    std::string statsJson;  // optional
    std::string camera;     // name, node name or index (Scene::camera); empty = first in the file

    Method method = Method::Splat;
    int width = 500;   // 0: from height and the camera's aspect
    int height = 0;    // 0: from width and the camera's aspect
    int spp = 0;       // samples per pixel; 0: the method's default (splat 4, path 16)
    int maxDepth = kDefaultMaxDepth;
    uint64_t seed = 0;
    int threads = 0;         // 0: all hardware threads
    uint64_t maxMemory = 0;  // bytes a render may need (memory.h's estimate); 0: what the machine has available
    // Passes (splat: each a new eye pass and new photons, kernels shrinking from pass to
    // pass; path: each --spp samples a pixel), averaged; 0: the method's default (splat 8,
    // path 1). With a time limit, passes are rendered until the time is up (at least one)
    // and `passes` is ignored. Splat's 8: one pass shows the kernels' blotches, eight little.
    int passes = 0;
    double timeLimit = 0.0;  // seconds; > 0: render passes until the time is up
    // Splat, light sampled in a direct film: after the passes, this many passes of the direct film
    // alone (docs/design.md §9). With a time limit, the time no whole pass fits in goes to
    // such passes by itself, and this stays 0.
    int filmPasses = 0;
    // Kernel shrinkage between passes (Knaus & Zwicker 2011): r²(i+1) = r²(i)·(i + α)/(i + 1).
    float alpha = 2.f / 3.f;
    // The indirect kernels' scale, after the clamps: > 0 as given; 0 (auto): with direct light
    // by sampling and more than one pass, chosen by the first pass from the bias and the noise
    // it measures (splat/kernel_scale.h), else 1.
    float kernelScale = 0.f;
    float exposure = 0.f;    // PNG preview, stops
    // Non-empty: the EXR's channels are named as Blender's multilayer EXR of this view layer
    // (writeExrTo), as the Blender add-on loads them.
    std::string blenderLayer;
    // A walkthrough (lib/walkthrough.h): frames firstFrame, firstFrame + frameStep, … up to
    // lastFrame of the file's animations, frame n at time n / fps, each written to its own outputs
    // (framePath). firstFrame < 0: a still, the nodes as the file writes them.
    int firstFrame = -1, lastFrame = -1;
    int frameStep = 1;
    float fps = 24.f;
    std::string animation;     // the one animation to play, by name or index; empty: all of them
    bool skipExisting = false;  // skip the frames whose outputs all exist
    static constexpr int kMaxFrame = 1000000;
    bool walkthrough() const { return firstFrame >= 0; }
    int frameCount() const { return walkthrough() ? (lastFrame - firstFrame) / frameStep + 1 : 0; }
    // ≥ 0: replay one photon ray, number `replayIndex` (in merge order) of pass `replayPass`:
    // the image is that ray's splat alone, and its record is reported (docs/design.md §9).
    int replayPass = -1;
    int64_t replayIndex = -1;
    bool replays() const { return replayPass >= 0; }

    // The environment light (docs/design.md §4): an equirectangular OpenEXR `env` in Blender's
    // world orientation, times `envStrength`, turned `envRotation` degrees about the up axis as
    // Blender's Mapping node Z rotation turns it; or a uniform sky of radiance `sky` (black: none).
    std::string env;
    float envStrength = 1.f;
    float envRotation = 0.f;
    Vec3 sky{0.f};
    // The render's environment: `env` or `sky` where given, else the scene's own
    // (Scene::environment). Loads the image; throws Error naming the file.
    Environment environment(const Scene& scene) const;

    // Photons (docs/design.md §7): total M, the split direct/indirect/caustic, the photons wanted
    // under a kernel (k) and the radius clamps in voxels, per class.
    DirectMethod direct = DirectMethod::Sample;
    // Direct light by sampling (docs/design.md §4): a direct film of `directSpp` camera samples a
    // pixel and pass, apart from the photons' receivers, each with `lightSamples` light samples
    // (and as many BSDF samples) stratified across the pixel's samples: 16 × 1 gives the direct
    // layer a lower error in less time than 8 light samples at each of the 4 receivers, and
    // under a point light a tenth of it (edges and shadows get 16 camera samples). directSpp 0: at the receivers, as the paper's eye samples (emission at 4 samples a pixel).
    int lightSamples = 1;
    int directSpp = 16;
    // Defaults and the measurements behind them: PhotonSettings.
    int64_t photons = PhotonSettings{}.photons;
    // Photon rounds a pass (docs/design.md §9): each traces `photons` more paths and splats them
    // on the pass's eye samples. 0: auto, 1 but under a time limit what the first pass measures
    // (photonRoundsAuto()).
    int photonRounds = 0;
    static constexpr int kMaxPhotonRounds = 64;
    // The split as given; photonSplit() is what the render uses: unless set, direct light by
    // sampling traces no direct photons (the paper's 0.5 : 0.3 for the others).
    ClassTriple split = PhotonSettings{}.split;
    bool splitSet = false;
    ClassTriple kernelPhotons = PhotonSettings{}.k;
    ClassTriple minRadius = PhotonSettings{}.minRadius;
    ClassTriple maxRadius = PhotonSettings{}.maxRadius;
    Visibility visibility = Visibility::Auto;
    // Probes a photon for its kernel's coverage with `visibility` rays (0: none, the kernels'
    // light past edges and corners lost). Defaults: CoverageSettings.
    int coverageProbes = CoverageSettings{}.probes;
    // The least share of a kernel a photon's flux (or, at the samples, a sample's light) is divided
    // by: a bound on its weight against fireflies, at a measured bias (CoverageSettings::minCoverage).
    // 0: none.
    float minCoverage = CoverageSettings{}.minCoverage;
    // Where a kernel lands on one plane, its loss at edges and corners is corrected at each sample
    // (true: KernelEdge) rather than by dividing the photon's flux (false).
    bool coverageAtSamples = CoverageSettings{}.atSamples;
    // The indirect photons' receivers, this many of the smallest indirect kernel radius apart
    // (IrradianceSettings); 0: every eye sample. Only with visibility by rays.
    float receiverSpacing = IrradianceSettings{}.spacing;

    // Occlusion grid (docs/design.md §5–6).
    int grid = GridSettings{}.resolution;             // voxels along the scene's longest axis
    std::string voxelizer = GridSettings{}.voxelizer;  // auto (GPU on a hardware EGL device, else CPU), gpu, cpu
    std::string vdb;                                  // optional: write the grid used as .vdb
    std::string cacheDir;                             // optional: voxel cache directory (<key>.vdb files)
    GridSettings gridSettings() const { return {grid, voxelizer, vdb, cacheDir}; }

    int samplesPerPixel() const { return spp > 0 ? spp : method == Method::Path ? PathSettings{}.spp : EyePassSettings{}.spp; }
    int passCount() const { return replays() ? 1 : renderPassCount(); }
    // The passes of the render, a replayed one's too (its first pass chooses the kernel scale
    // for this many).
    int renderPassCount() const { return passes > 0 ? passes : method == Method::Path ? 1 : 8; }
    // The most passes whose camera sample indices (pass × samples a pixel and pass, for the
    // receivers and the direct film) fit the 31 bits they are counted in.
    int maxPasses() const;
    bool directBySampling() const { return direct == DirectMethod::Sample; }
    ClassTriple photonSplit() const;
    bool splats() const { return method != Method::Path; }
    // The visibility a splat render uses: `visibility` with Auto resolved.
    Visibility visibilityUsed() const {
        return visibility != Visibility::Auto ? visibility : directBySampling() ? Visibility::Rays : Visibility::Mask;
    }
    // Whether the render needs the voxel grid's occlusion (the mask), not only its geometry.
    bool probesKernelScale() const {
        return method == Method::Splat && directBySampling() && kernelScale == 0.f && (timeLimit > 0.0 || renderPassCount() > 1);
    }
    // Whether the first pass chooses the photon rounds of the others: under a time limit, where
    // it probes the kernel scale (its noise is what the rounds lower) and has a direct film.
    bool photonRoundsAuto() const {
        return photonRounds == 0 && timeLimit > 0.0 && probesKernelScale() && directSpp > 0;
    }
    float kernelScaleOrOne() const { return kernelScale > 0.f ? kernelScale : 1.f; }
    bool needsMask() const { return method == Method::Splat && visibilityUsed() == Visibility::Mask; }
    // Whether the receiver rules alone decide visibility (kernels reaching to the scene's bounds,
    // their coverage measured).
    bool visibilityByRays() const { return method == Method::Splat && visibilityUsed() == Visibility::Rays; }
    // Whether indirect photons land on sparse receivers (irradiance.h).
    bool sparseReceivers() const { return visibilityByRays() && receiverSpacing > 0.f; }
    void validate() const;
    // The grid settings only (validate() includes them): for commands without an image.
    void validateGrid() const;
    // The walkthrough's settings only (validate() includes them).
    void validateFrames() const;
    // Width and height for a camera of aspect `aspect` (0: unknown, taken as 1).
    void resolution(float aspect, int& w, int& h) const;
    ImageAttributes attributes() const;  // for the EXR header
};

}  // namespace rs
