// Shaders embedded at build time (glsl/ → shaders_embedded.h by scripts/embed_shaders.py,
// docs/design.md §1) and compiled into GL programs. Needs a current GpuContext. Compile and
// link errors throw Error(Gpu) naming the shader file and line ("glsl/voxelize.frag:12:
// error: …"). GL handles are plain unsigned ints so that this header includes no GL.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace rs {

// The embedded text of a shader by file name ("glsl/voxelize.frag"); throws Error(Gpu)
// when there is no such shader.
const std::string& shaderSource(const std::string& name);

// Compiles and links the named embedded shaders (stage from the extension: .vert, .geom,
// .frag, .comp) into a program; the caller owns it (glDeleteProgram or GlProgram).
unsigned compileProgram(const std::vector<std::string>& names);

// The same from (name, source) pairs; the name is used in messages and for the stage.
unsigned compileProgramFromSources(const std::vector<std::pair<std::string, std::string>>& shaders);

// Rewrites a driver's info log so that each line names the file: Mesa's "0:12(3): error: x"
// and NVIDIA's "0(12) : error C0000: x" become "glsl/a.frag:12: error: x"; other lines are
// prefixed with "glsl/a.frag: ". Lines are joined with " | " (errors are one line).
std::string formatShaderLog(const std::string& name, const std::string& log);

// Owns a program; deletes it with the context still current.
class GlProgram {
public:
    explicit GlProgram(unsigned id = 0) : id_(id) {}
    ~GlProgram();
    GlProgram(const GlProgram&) = delete;
    GlProgram& operator=(const GlProgram&) = delete;
    unsigned id() const { return id_; }
    int uniform(const char* name) const;  // -1 when the linker dropped it

private:
    unsigned id_;
};

}  // namespace rs
