// What a render will need in memory, estimated before anything large is allocated, so that
// settings that fit the ranges but not the machine fail at once with one line instead of
// minutes later or in the kernel's OOM killer. The figures are the largest buffers each stage
// holds at its peak, measured on the data/ scenes (stats-json's *_mb counts and /usr/bin/time's
// maximum resident size), rounded up.
#pragma once

#include <cstdint>
#include <string>

#include "config.h"

namespace rs {

struct MemoryEstimate {
    double grid = 0, tree = 0, eye = 0, photons = 0, film = 0, splat = 0, bvh = 0, base = 0;  // bytes
    double store = 0;  // a walkthrough's photons of every pass, kept across its frames
    double total() const { return grid + tree + eye + photons + film + splat + bvh + base + store; }
    std::string describe() const;  // "2.1 GiB (grid 1.6, eye samples 0.2, …)"
};

// For a render of `triangles` triangles at width × height on `threads` threads; the grid is
// the one `cfg.grid` gives over the scene's bounds (dims) and exists only when the render
// needs it (splat methods, or --vdb / --cache with the path tracer). `keepsPhotons`: a
// walkthrough that keeps every pass's photons for its frames (PhotonStore).
MemoryEstimate estimateMemory(const RenderConfig& cfg, const int gridDims[3], size_t triangles, int width, int height,
                              int threads, bool keepsPhotons = false);

// The memory this process may still use: the smaller of MemAvailable (/proc/meminfo) and
// what its cgroup allows; 0 when neither can be read.
uint64_t availableMemory();

// Throws Error(Config) naming the estimate and the limit when the estimate exceeds
// `limitBytes` (0: availableMemory(); nothing is checked when that is unknown).
// `sharers`: the processes on this machine that render at once (an MPI job's ranks on it), each
// allowed an equal part of the available memory.
void checkMemory(const MemoryEstimate& estimate, uint64_t limitBytes, int sharers = 1);

}  // namespace rs
