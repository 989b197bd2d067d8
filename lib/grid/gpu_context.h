// GpuContext: a headless OpenGL 4.5 core context through EGL (docs/design.md §5), current on the
// thread that creates it, for as long as the object lives (RAII). Device order: a hardware
// EGL device (EGL_EXT_platform_device), else Mesa's software device (llvmpipe), else the
// surfaceless platform on EGL_DEFAULT_DISPLAY. GL debug output records errors; stages call
// check() at their boundaries to turn what was recorded into Error(Gpu) (errors: docs/design.md §10).
// EGL and GL headers stay in gpu_context.cpp (docs/design.md §1).
#pragma once

#include <memory>
#include <string>

namespace rs {

class GpuContext {
public:
    // Throws Error(Gpu) with a one-line reason when no EGL display or context can be made.
    GpuContext();
    ~GpuContext();
    GpuContext(const GpuContext&) = delete;
    GpuContext& operator=(const GpuContext&) = delete;

    // "NVIDIA Corporation, NVIDIA H100 …, 4.5.0 NVIDIA …; EGL device platform (hardware)"
    std::string description() const;

    // Throws Error(Gpu) naming `stage` when GL reported an error since the last check.
    void check(const char* stage);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Whether EGL lists a hardware device (one without EGL_MESA_device_software): asks for the
// devices only, makes no display or context. False in a build without EGL.
bool hasHardwareGpu();

// Creates a context and returns its description (for `raysplat info --gpu`); throws
// Error(Gpu) when there is none (including a build without EGL).
std::string describeGpu();

}  // namespace rs
