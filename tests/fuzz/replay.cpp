// Replays the fuzzers' findings (tests/fuzz/regressions/<target>/*) and the seed corpora through
// the same entry points as the fuzzers, without clang: every file must come back as a clean
// Error or a success, never a crash (the sanitizer build of CI turns memory errors into
// failures too).
//
//   replay DIR...   each DIR named after its target (gltf, vdb, cli)
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "targets.h"

int main(int argc, char** argv) {
    size_t files = 0;
    for (int i = 1; i < argc; ++i) {
        const std::filesystem::path dir(argv[i]);
        const rs::fuzz::Target target = rs::fuzz::targetNamed(dir.filename().string());
        if (!target) {
            std::fprintf(stderr, "replay: %s is not named after a target (gltf, vdb, cli)\n", argv[i]);
            return 1;
        }
        std::vector<std::filesystem::path> inputs;
        for (const auto& entry : std::filesystem::directory_iterator(dir))
            if (entry.is_regular_file()) inputs.push_back(entry.path());
        std::sort(inputs.begin(), inputs.end());
        for (const auto& path : inputs) {
            std::ifstream f(path, std::ios::binary);
            const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
            std::printf("%s\n", path.string().c_str());
            std::fflush(stdout);
            target(bytes.data(), bytes.size());
            ++files;
        }
    }
    std::printf("replayed %zu files\n", files);
    return files > 0 ? 0 : 1;
}
