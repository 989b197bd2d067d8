#include "targets.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include "cli/options.h"
#include "core/error.h"
#include "core/log.h"
#include "grid/vdb_io.h"
#include "scene/scene.h"

namespace rs::fuzz {

namespace {

// The readers take paths: each input goes to a file of this process's own in /tmp.
std::string writeInput(const char* extension, const uint8_t* data, size_t size) {
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("raysplat_fuzz_" + std::to_string(getpid()) + extension)).string();
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    return path;
}

}  // namespace

void loadGltf(const uint8_t* data, size_t size) {
    if (size == 0) return;
    const std::string path = writeInput(data[0] % 2 ? ".glb" : ".gltf", data + 1, size - 1);
    try {
        const Scene scene = loadScene(path, silentReporter());
        // An animated file: its poses before, inside and after its keys, and the scene flattened
        // as posed, as a walkthrough evaluates them.
        const SceneAnimation& a = scene.animation;
        if (a.animated()) {
            const std::vector<int> all = a.select("", path);
            const float start = a.start(all), end = a.end(all);
            for (float t : {start - 1.f, 0.5f * (start + end), end + 1.f}) {
                const std::vector<Mat4> pose = a.pose(all, t);
                for (size_t c = 0; c < scene.cameras.size(); ++c) placeCamera(scene.cameras[c], a.worldFrom(a.cameraNode[c], pose));
            }
            const std::vector<Mat4> pose = a.pose(all, 0.5f * (start + end));
            loadScene(path, silentReporter(), 0, &pose);
        }
    } catch (const Error&) {
    }
    std::remove(path.c_str());
}

void readVdbFile(const uint8_t* data, size_t size) {
    const std::string path = writeInput(".vdb", data, size);
    try {
        readCacheVdb(path);
    } catch (const Error&) {
    }
    std::remove(path.c_str());
}

void parseCommandLine(const uint8_t* data, size_t size) {
    if (size == 0) return;
    std::vector<std::string> words = {"raysplat", data[0] % 2 ? "voxelize" : "render"};
    std::string word;
    for (size_t i = 1; i < size; ++i) {
        if (data[i] == 0) {
            words.push_back(word);
            word.clear();
        } else {
            word += char(data[i]);
        }
    }
    if (size > 1) words.push_back(word);
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    try {
        if (data[0] % 2)
            cli::parseVoxelize(int(words.size()), argv.data());
        else
            cli::parseRender(int(words.size()), argv.data());
    } catch (const Error&) {
    }
}

Target targetNamed(const std::string& name) {
    if (name == "gltf") return loadGltf;
    if (name == "vdb") return readVdbFile;
    if (name == "cli") return parseCommandLine;
    return nullptr;
}

}  // namespace rs::fuzz
