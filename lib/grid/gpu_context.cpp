// Headless EGL context (docs/design.md §5), with no display or window, in this sequence:
// eglQueryDevicesEXT → eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT) → eglInitialize →
// eglBindAPI(EGL_OPENGL_API) → context 4.5 core → eglMakeCurrent with no surface.
// Fallback: EGL_PLATFORM_SURFACELESS_MESA on EGL_DEFAULT_DISPLAY. Every display that fails
// adds its reason to the one-line error thrown when none works.
#include "grid/gpu_context.h"

#include "core/error.h"

#ifdef RAYSPLAT_HAVE_EGL

#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES
#include <GL/glcorearb.h>

#include <cstring>
#include <vector>

namespace rs {

namespace {

std::string eglErrorName(EGLint e) {
    switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    default: {
        char buf[32];
        std::snprintf(buf, sizeof buf, "EGL error 0x%x", unsigned(e));
        return buf;
    }
    }
}

bool hasExtension(const char* list, const char* name) {
    if (!list) return false;
    size_t n = std::strlen(name);
    for (const char* p = list; (p = std::strstr(p, name)); p += n)
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
    return false;
}

struct Candidate {
    EGLDisplay display;
    std::string label;
    bool software;
};

struct Device {
    EGLDeviceEXT device;
    const char* extensions;  // the device's, or null
    bool software;           // EGL_MESA_device_software
};

// The devices EGL lists (EGL_EXT_platform_device); none, with the reason added to `reasons`,
// when it cannot list them.
std::vector<Device> listDevices(const char* clientExt, std::string& reasons) {
    auto queryDevices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    auto queryDeviceString =
        reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
    std::vector<Device> out;
    if (!queryDevices || !queryDeviceString || !hasExtension(clientExt, "EGL_EXT_platform_device")) {
        reasons += "no EGL_EXT_platform_device; ";
        return out;
    }
    EGLDeviceEXT devices[16];
    EGLint count = 0;
    if (!queryDevices(16, devices, &count) || count <= 0) {
        reasons += "eglQueryDevicesEXT found no device; ";
        return out;
    }
    for (EGLint i = 0; i < count; ++i) {
        const char* ext = queryDeviceString(devices[i], EGL_EXTENSIONS);
        out.push_back({devices[i], ext, hasExtension(ext, "EGL_MESA_device_software")});
    }
    return out;
}

// Hardware devices first, then software ones (llvmpipe), then the surfaceless platform.
std::vector<Candidate> candidateDisplays(std::string& reasons) {
    std::vector<Candidate> out;
    const char* clientExt = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!clientExt) {
        reasons += "libEGL has no client extensions (" + eglErrorName(eglGetError()) + ")";
        return out;
    }
    auto getPlatformDisplay =
        reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    auto queryDeviceString =
        reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
    if (!getPlatformDisplay) {
        reasons += "no eglGetPlatformDisplayEXT";
        return out;
    }
    std::vector<Candidate> software;
    const std::vector<Device> devices = listDevices(clientExt, reasons);
    for (size_t i = 0; i < devices.size(); ++i) {
        const Device& dev = devices[i];
        const char* file = hasExtension(dev.extensions, "EGL_EXT_device_drm")
                               ? queryDeviceString(dev.device, EGL_DRM_DEVICE_FILE_EXT)
                               : nullptr;
        EGLDisplay d = getPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, dev.device, nullptr);
        std::string label = "EGL device " + std::to_string(i) + (file ? std::string(" (") + file + ")" : "");
        if (d == EGL_NO_DISPLAY) {
            reasons += label + ": no display (" + eglErrorName(eglGetError()) + "); ";
            continue;
        }
        (dev.software ? software : out).push_back({d, label, dev.software});
    }
    out.insert(out.end(), software.begin(), software.end());
    if (hasExtension(clientExt, "EGL_MESA_platform_surfaceless")) {
        EGLDisplay d = getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
        if (d != EGL_NO_DISPLAY) out.push_back({d, "EGL surfaceless platform", false});
        else reasons += "surfaceless platform: no display (" + eglErrorName(eglGetError()) + "); ";
    } else {
        reasons += "no EGL_MESA_platform_surfaceless; ";
    }
    return out;
}

void APIENTRY onGlDebug(GLenum, GLenum type, GLuint, GLenum severity, GLsizei, const GLchar* message,
                          const void* user) {
    if (type != GL_DEBUG_TYPE_ERROR && severity != GL_DEBUG_SEVERITY_HIGH) return;
    auto* errors = static_cast<std::vector<std::string>*>(const_cast<void*>(user));
    if (errors->size() < 8) errors->push_back(message ? message : "(no message)");
}

}  // namespace

struct GpuContext::Impl {
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;
    std::string platform;
    bool software = false;
    std::vector<std::string> errors;  // written by onGlDebug on this (the owning) thread
};

GpuContext::GpuContext() : impl_(std::make_unique<Impl>()) {
    std::string reasons;
    for (const Candidate& c : candidateDisplays(reasons)) {
        EGLint major = 0, minor = 0;
        if (!eglInitialize(c.display, &major, &minor)) {
            reasons += c.label + ": eglInitialize failed (" + eglErrorName(eglGetError()) + "); ";
            continue;
        }
        auto fail = [&](const char* what) {
            reasons += c.label + ": " + what + " (" + eglErrorName(eglGetError()) + "); ";
            eglTerminate(c.display);
        };
        if (!eglBindAPI(EGL_OPENGL_API)) { fail("no desktop OpenGL"); continue; }
        const EGLint configAttribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, EGL_PBUFFER_BIT,
                                        EGL_NONE};
        EGLConfig config = nullptr;
        EGLint configs = 0;
        if (!eglChooseConfig(c.display, configAttribs, &config, 1, &configs) || configs < 1) {
            // Surfaceless contexts do not need a config where EGL_KHR_no_config_context is there.
            if (!hasExtension(eglQueryString(c.display, EGL_EXTENSIONS), "EGL_KHR_no_config_context")) {
                fail("no OpenGL config");
                continue;
            }
            config = EGL_NO_CONFIG_KHR;
        }
        const EGLint contextAttribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                         EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                         EGL_CONTEXT_OPENGL_DEBUG, EGL_TRUE, EGL_NONE};
        EGLContext ctx = eglCreateContext(c.display, config, EGL_NO_CONTEXT, contextAttribs);
        if (ctx == EGL_NO_CONTEXT) { fail("no OpenGL 4.5 core context"); continue; }
        if (!eglMakeCurrent(c.display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
            eglDestroyContext(c.display, ctx);
            fail("cannot make the context current without a surface");
            continue;
        }
        impl_->display = c.display;
        impl_->context = ctx;
        impl_->platform = c.label + ", EGL " + std::to_string(major) + "." + std::to_string(minor);
        const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
        impl_->software = c.software || (renderer && (std::strstr(renderer, "llvmpipe") || std::strstr(renderer, "softpipe")));
        break;
    }
    if (impl_->context == EGL_NO_CONTEXT) {
        if (reasons.size() >= 2 && reasons.compare(reasons.size() - 2, 2, "; ") == 0) reasons.resize(reasons.size() - 2);
        throw Error(ErrorKind::Gpu, "no usable EGL display: " + reasons);
    }
    glEnable(GL_DEBUG_OUTPUT);
    glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);  // errors are recorded on the thread that caused them
    glDebugMessageCallback(onGlDebug, &impl_->errors);
}

GpuContext::~GpuContext() {
    glDebugMessageCallback(nullptr, nullptr);
    eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(impl_->display, impl_->context);
    eglTerminate(impl_->display);
    eglReleaseThread();
}

std::string GpuContext::description() const {
    auto str = [](GLenum name) {
        const char* s = reinterpret_cast<const char*>(glGetString(name));
        return std::string(s ? s : "?");
    };
    return str(GL_VENDOR) + ", " + str(GL_RENDERER) + ", OpenGL " + str(GL_VERSION) + "; " + impl_->platform +
           (impl_->software ? " (software)" : " (hardware)");
}

void GpuContext::check(const char* stage) {
    std::string message;
    for (const std::string& e : impl_->errors) message += (message.empty() ? "" : "; ") + e;
    impl_->errors.clear();
    // glGetError catches what a driver without debug output reports.
    for (GLenum e; (e = glGetError()) != GL_NO_ERROR;) {
        if (!message.empty()) continue;  // the debug message already says more
        char buf[48];
        std::snprintf(buf, sizeof buf, "glGetError 0x%04x", unsigned(e));
        message = buf;
    }
    if (!message.empty()) throw Error(ErrorKind::Gpu, std::string("OpenGL error during ") + stage + ": " + message);
}

std::string describeGpu() {
    GpuContext context;
    return context.description();
}

bool hasHardwareGpu() {
    const char* clientExt = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!clientExt) return false;
    std::string reasons;
    for (const Device& d : listDevices(clientExt, reasons))
        if (!d.software) return true;
    return false;
}

}  // namespace rs

#else  // !RAYSPLAT_HAVE_EGL

namespace rs {

struct GpuContext::Impl {};

GpuContext::GpuContext() { throw Error(ErrorKind::Gpu, "built without EGL (meson option -Degl=enabled)"); }
GpuContext::~GpuContext() = default;
std::string GpuContext::description() const { return {}; }
void GpuContext::check(const char*) {}
std::string describeGpu() { throw Error(ErrorKind::Gpu, "built without EGL (meson option -Degl=enabled)"); }
bool hasHardwareGpu() { return false; }

}  // namespace rs

#endif
