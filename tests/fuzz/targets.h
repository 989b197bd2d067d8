// The fuzz targets (scripts/fuzz.sh runs them under libFuzzer with clang): each takes one input
// as bytes and feeds it to a file reader or the command line through its public entry point, the way a user's file
// reaches it. A clean Error is the expected outcome for bad input; a crash, a hang, a sanitizer
// report or a runaway allocation is a defect. tests/fuzz/replay.cpp replays every file kept in
// tests/fuzz/regressions/<target>/ through the same functions in the normal test suite.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace rs::fuzz {

// The first byte picks the form: even .gltf (JSON, buffers as data URIs or missing files),
// odd .glb; the rest is the file.
void loadGltf(const uint8_t* data, size_t size);
// A .vdb file as the voxel cache reads it (checksum first, then OpenVDB).
void readVdbFile(const uint8_t* data, size_t size);

// A command line as the render or voxelize command parses it: the first byte picks the
// command (even render, odd voxelize), the rest is the arguments, separated by NUL bytes.
void parseCommandLine(const uint8_t* data, size_t size);

// The target of a name ("gltf", "vdb", "cli"), or nullptr.
using Target = void (*)(const uint8_t*, size_t);
Target targetNamed(const std::string& name);

}  // namespace rs::fuzz
