// Embedded shader lookup and compilation (see shaders.h).
#include "grid/shaders.h"

#include <algorithm>
#include <cctype>
#include <map>

#define GL_GLEXT_PROTOTYPES
#include <GL/glcorearb.h>

#include "core/error.h"
#include "shaders_embedded.h"

namespace rs {

namespace {

GLenum stageOf(const std::string& name) {
    auto endsWith = [&](const char* ext) {
        std::string e(ext);
        return name.size() >= e.size() && name.compare(name.size() - e.size(), e.size(), e) == 0;
    };
    if (endsWith(".vert")) return GL_VERTEX_SHADER;
    if (endsWith(".geom")) return GL_GEOMETRY_SHADER;
    if (endsWith(".frag")) return GL_FRAGMENT_SHADER;
    if (endsWith(".comp")) return GL_COMPUTE_SHADER;
    throw Error(ErrorKind::Gpu, name + ": unknown shader stage (expected .vert, .geom, .frag or .comp)");
}

// Parses a leading "0:12(3): " (Mesa) or "0(12) : " (NVIDIA) and returns the line, or -1.
int logLine(const std::string& line, size_t& rest) {
    size_t i = 0;
    auto digits = [&] {
        size_t b = i;
        while (i < line.size() && std::isdigit(static_cast<unsigned char>(line[i]))) ++i;
        return i > b;
    };
    if (!digits()) return -1;
    int number = -1;
    if (i < line.size() && line[i] == ':') {  // Mesa: source:line(column):
        size_t b = ++i;
        if (!digits()) return -1;
        number = std::stoi(line.substr(b, i - b));
        if (i < line.size() && line[i] == '(') {
            while (i < line.size() && line[i] != ')') ++i;
            ++i;
        }
    } else if (i < line.size() && line[i] == '(') {  // NVIDIA: source(line)
        size_t b = ++i;
        if (!digits()) return -1;
        number = std::stoi(line.substr(b, i - b));
        if (i >= line.size() || line[i] != ')') return -1;
        ++i;
    } else {
        return -1;
    }
    while (i < line.size() && line[i] == ' ') ++i;
    if (i >= line.size() || line[i] != ':') return -1;
    ++i;
    while (i < line.size() && line[i] == ' ') ++i;
    rest = i;
    return number;
}

GLuint compileShader(const std::string& name, const std::string& source) {
    GLenum stage = stageOf(name);
    GLuint shader = glCreateShader(stage);
    const char* text = source.c_str();
    glShaderSource(shader, 1, &text, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        GLint length = 0;
        glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
        std::string log(size_t(std::max(length, 1)), '\0');
        glGetShaderInfoLog(shader, length, nullptr, log.data());
        glDeleteShader(shader);
        throw Error(ErrorKind::Gpu, "shader compile failed: " + formatShaderLog(name, log.c_str()));
    }
    return shader;
}

}  // namespace

std::string formatShaderLog(const std::string& name, const std::string& log) {
    std::string out;
    size_t start = 0;
    while (start < log.size()) {
        size_t end = log.find('\n', start);
        if (end == std::string::npos) end = log.size();
        std::string line = log.substr(start, end - start);
        start = end + 1;
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
        if (line.empty()) continue;
        size_t rest = 0;
        int number = logLine(line, rest);
        std::string formatted = number >= 0 ? name + ":" + std::to_string(number) + ": " + line.substr(rest)
                                            : name + ": " + line;
        out += (out.empty() ? "" : " | ") + formatted;
    }
    return out.empty() ? name + ": (empty info log)" : out;
}

const std::string& shaderSource(const std::string& name) {
    static const std::map<std::string, std::string> sources = [] {
        std::map<std::string, std::string> m;
        for (const embedded::Shader& s : embedded::kShaders) m[s.name] = s.source;
        return m;
    }();
    auto it = sources.find(name);
    if (it == sources.end()) throw Error(ErrorKind::Gpu, "no embedded shader '" + name + "'");
    return it->second;
}

unsigned compileProgram(const std::vector<std::string>& names) {
    std::vector<std::pair<std::string, std::string>> shaders;
    for (const std::string& n : names) shaders.emplace_back(n, shaderSource(n));
    return compileProgramFromSources(shaders);
}

unsigned compileProgramFromSources(const std::vector<std::pair<std::string, std::string>>& shaders) {
    std::vector<GLuint> compiled;
    try {
        for (const auto& [name, source] : shaders) compiled.push_back(compileShader(name, source));
    } catch (...) {
        for (GLuint s : compiled) glDeleteShader(s);
        throw;
    }
    GLuint program = glCreateProgram();
    for (GLuint s : compiled) glAttachShader(program, s);
    glLinkProgram(program);
    for (GLuint s : compiled) glDeleteShader(s);  // flagged; freed with the program
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        GLint length = 0;
        glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
        std::string log(size_t(std::max(length, 1)), '\0');
        glGetProgramInfoLog(program, length, nullptr, log.data());
        glDeleteProgram(program);
        std::string names;
        for (const auto& s : shaders) names += (names.empty() ? "" : " + ") + s.first;
        throw Error(ErrorKind::Gpu, "shader link failed: " + formatShaderLog(names, log.c_str()));
    }
    return program;
}

GlProgram::~GlProgram() {
    if (id_) glDeleteProgram(id_);
}

int GlProgram::uniform(const char* name) const { return glGetUniformLocation(id_, name); }

}  // namespace rs
