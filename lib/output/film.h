// Film: the image being rendered, kept as separate light-transport layers (docs/design.md §8, §10)
// whose sum is the beauty image, plus first-hit albedo and normal for denoisers.
// Raster space: pixel (x, y) covers [x, x+1) × [y, y+1), y down, centre at +0.5.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/math.h"

namespace rs {

enum Layer { kDirect = 0, kIndirect, kCaustic, kEmission, kLayerCount };
const char* layerName(int layer);

struct Film {
    int width = 0, height = 0;
    std::vector<Vec3> layers[kLayerCount];
    std::vector<Vec3> albedo, normal;

    Film() = default;
    Film(int w, int h);
    size_t pixelCount() const { return size_t(width) * height; }
    Vec3 beauty(size_t i) const;
    std::vector<Vec3> beautyImage() const;
    void add(const Film& other);  // pixelwise sum of every buffer
    void scale(float s);
};

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
// (the caller stages it: StagedFiles); errors name `path`.
void writeExrTo(const std::string& file, const std::string& path, const Film& film, const ImageAttributes& attributes);

// Relative MSE of `a` against the reference `ref`, per channel: mean of (a − r)² / (r² + ε),
// ε = 0.01 keeping dark pixels from dominating. The figure the tests and benchmarks report.
double relativeMse(const std::vector<Vec3>& a, const std::vector<Vec3>& ref);

// Writes `contents` to `file` as is (the caller stages it); throws Error(Io) naming `path`.
void writeFileTo(const std::string& file, const std::string& path, const std::string& contents);
// The temporary name used for an atomic write of `path`, in the same directory.
std::string temporaryPathFor(const std::string& path);
// Renames tmp to path; on failure removes tmp and throws Error(Io) naming path.
void commitTemporary(const std::string& tmp, const std::string& path);

// Several outputs that appear together or not at all: each is written under its temporary
// name; commit() renames them all; files not committed are removed on destruction.
class StagedFiles {
public:
    ~StagedFiles();
    std::string stage(const std::string& path);  // returns the temporary name to write
    void commit();

private:
    std::vector<std::pair<std::string, std::string>> files_;  // temporary, final
};

}  // namespace rs
