// Images on disk: the film as OpenEXR (every layer a channel group, settings and timings as
// header attributes), read back for comparisons, and the PNG preview (docs/design.md §10).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "output/film.h"

namespace rs {

// Header attributes of the EXR (string values), e.g. method, spp, seed, timings.
using ImageAttributes = std::map<std::string, std::string>;

// An EXR read back: channel name → values (row-major), and the string attributes.
struct ExrImage {
    int width = 0, height = 0;
    std::map<std::string, std::vector<float>> channels;
    ImageAttributes attributes;
    std::vector<Vec3> rgb(const std::string& prefix = "") const;  // "" or "direct." …
};
ExrImage readExr(const std::string& path);

// The bytes of the PNG preview: exposure in stops, clamp, sRGB transfer, 8-bit RGB.
std::string encodePng(const Film& film, float exposureStops);
// Writes beauty R,G,B plus <layer>.R/G/B, albedo.*, normal.* as float channels to `file` as is
// (the caller stages it: StagedFiles); errors name `path`. The ZIP blocks are compressed on
// `threads` threads (≥ 1); the file's bytes do not depend on how many. With a `blenderLayer`,
// the channels are named as Blender's multilayer EXR of that view layer: <layer>.Combined.RGBA
// (alpha 1), <layer>.Direct.RGB … <layer>.Albedo.RGB, <layer>.Normal.XYZ (in Blender's axes, Z up),
// which Blender's RenderResult.load_from_file and its image editor read as passes.
void writeExrTo(const std::string& file, const std::string& path, const Film& film, const ImageAttributes& attributes,
                int threads = 1, const std::string& blenderLayer = "");

}  // namespace rs
