#include "memory.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "core/error.h"
#include "grid/occlusion_grid.h"
#include "grid/voxelize.h"
#include "occlusion/kdtree.h"
#include "splat/photons.h"

namespace rs {

namespace {

constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;

// Per eye sample: the sample and a lobe at most, the eye pass's rows appended into one array
// (twice), and the tree build's keys, flags, order and one permuted array.
constexpr double kBytesPerEyeSample = 2 * double(EyeSamples::kBytesPerSample + sizeof(GlossyLobe)) + 8 + 2 + 4 + 12;
// Per pixel: the passes' fixed-point sum (six RGB buffers of 8-byte integers: layers, albedo,
// normal), a pass's float film, and one buffer's copy for a distributed render's reduction.
constexpr double kFilmBytesPerPixel = 6 * 3 * 8 + 6 * 12 + 3 * 8;
// Per pixel, in the first pass where it measures the kernel scale (kernel_probe.h): four
// half-images, four more where the probe widens to the rest of the pass's photons, and the two
// kept (RGB, 8 bytes; a splat's film of three layers instead of the four more).
constexpr double kProbeBytesPerPixel = (4 + 4 + 2) * 3 * 8;
// Per pixel, thread and photon class splatted onto the eye samples: the splat's fixed-point
// accumulators (RGB × 8 bytes). With sparse receivers the indirect photons land on the receivers
// instead (irradiance.h), whose buffers are a small fraction of these.
constexpr double kSplatBytesPerPixelThreadClass = 3 * 8;
// Per triangle: the scene's vertex data and Embree's BVH (high quality, robust).
constexpr double kBvhBytesPerTriangle = 3 * (12 + 12 + 8) + 160;
// The process before any of it: libraries, the EGL context (llvmpipe's is the largest), the
// threads' stacks. A Cornell box render at 200 px peaks at 181 MB, of which the above is 95.
constexpr double kBaseBytes = 128.0 * 1024 * 1024;

}  // namespace

std::string MemoryEstimate::describe() const {
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "%.2f GiB (grid %.2f, tree %.2f, eye samples %.2f, photons %.2f, film %.2f, splat buffers %.2f, "
                  "BVH %.2f, base %.2f",
                  total() / kGiB, grid / kGiB, tree / kGiB, eye / kGiB, photons / kGiB, film / kGiB, splat / kGiB,
                  bvh / kGiB, base / kGiB);
    std::string out = buf;
    if (store > 0.0) {
        std::snprintf(buf, sizeof buf, ", the walkthrough's photons %.2f", store / kGiB);
        out += buf;
    }
    return out + ")";
}

MemoryEstimate estimateMemory(const RenderConfig& cfg, const int dims[3], size_t triangles, int width, int height,
                              int threads, bool keepsPhotons) {
    MemoryEstimate m;
    m.base = kBaseBytes;
    const double pixels = double(width) * double(height);
    const bool grid = cfg.splats() || !cfg.vdb.empty() || !cfg.cacheDir.empty();
    if (grid) {
        const double voxels = double(dims[0]) * double(dims[1]) * double(dims[2]);
        // The counts, and the GPU voxelizer's read-back tile (RGBA32UI, 16 bytes a pixel).
        const double most = kMaxTilePixels;
        const double tile = std::min(4.0 * dims[0], most) * std::min(4.0 * std::max(dims[1], dims[2]), most);
        m.grid = voxels * kSideCount + tile * 16;
    }
    m.film = pixels * (kFilmBytesPerPixel + (cfg.probesKernelScale() ? kProbeBytesPerPixel : 0.0));
    m.bvh = double(triangles) * kBvhBytesPerTriangle;
    if (cfg.splats()) {
        const double voxels = double(dims[0]) * double(dims[1]) * double(dims[2]);
        m.eye = pixels * cfg.samplesPerPixel() * kBytesPerEyeSample;
        // About one node a brick of 4³ voxels: a bound on the tree's nodes and brick payloads.
        m.tree = voxels / double(kBrickSize * kBrickSize * kBrickSize) * sizeof(Node);
        m.photons = double(cfg.photons) * sizeof(PhotonRay) * 1.5;  // the map grows by doubling
        const int classes = (cfg.directBySampling() ? 0 : 1) + (cfg.sparseReceivers() ? 0 : 1) + 1;  // + caustic
        m.splat = pixels * kSplatBytesPerPixelThreadClass * classes * std::max(threads, 1);
        if (keepsPhotons) {
            // Every round of every pass (under a time limit, as many as a render without one),
            // each photon's ray and, corrected at the samples, its kernel's edges.
            const double perPhoton = sizeof(PhotonRay) + (cfg.coverageAtSamples ? sizeof(KernelEdge) : 0);
            m.store = double(cfg.photons) * cfg.renderPassCount() * std::max(cfg.photonRounds, 1) * perPhoton;
        }
    }
    return m;
}

uint64_t availableMemory() {
    uint64_t available = 0;
    std::ifstream meminfo("/proc/meminfo");
    for (std::string line; std::getline(meminfo, line);) {
        if (line.rfind("MemAvailable:", 0) != 0) continue;
        std::istringstream in(line.substr(13));
        uint64_t kb = 0;
        if (in >> kb) available = kb * 1024;
    }
    // cgroup v2: the limit of this process's group, less what it already uses.
    std::ifstream maxFile("/sys/fs/cgroup/memory.max"), currentFile("/sys/fs/cgroup/memory.current");
    std::string maxText;
    uint64_t current = 0;
    if (maxFile >> maxText && maxText != "max" && currentFile >> current) {
        const uint64_t limit = std::strtoull(maxText.c_str(), nullptr, 10);
        if (limit > current) available = available ? std::min(available, limit - current) : limit - current;
    }
    return available;
}

void checkMemory(const MemoryEstimate& estimate, uint64_t limitBytes, int sharers) {
    const bool machine = limitBytes == 0;
    sharers = std::max(sharers, 1);
    const uint64_t limit = machine ? availableMemory() / uint64_t(sharers) : limitBytes;
    if (limit == 0 || estimate.total() <= double(limit)) return;
    char each[64] = "";
    if (machine && sharers > 1) std::snprintf(each, sizeof each, " to each of the %d ranks on this machine", sharers);
    char buf[224];
    std::snprintf(buf, sizeof buf, " but %.2f GiB %s", double(limit) / kGiB,
                  machine ? (std::string("are available") + each + " (raise the limit with `max-memory` to try anyway)").c_str()
                          : "are allowed (`max-memory`)");
    throw Error(ErrorKind::Config, "this render needs about " + estimate.describe() + buf);
}

}  // namespace rs
