// Texture: one glTF image at 4 bytes a texel (8-bit RGBA; 8 bytes where the file is 16-bit),
// with a box-filtered mip chain (docs/design.md §3). Colour textures (base colour, emission) are
// sRGB-encoded and decoded at lookup through a 256-entry table; data textures (normal maps,
// metallic-roughness) are linear. Alpha is always linear. Row 0 is at v = 0; lookups wrap
// (glTF's default sampler, REPEAT).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/math.h"

namespace rs {

class Texture {
public:
    std::string name;  // "image 3 'wall.png'": how messages name it

    Texture() = default;
    // Level 0 from interleaved RGBA texels (width × height × 4 values; grey and grey+alpha
    // images expanded by the decoder), then the mip chain down to 1 × 1. withMips false: the
    // levels below 0 hold nothing until buildMipChain() (so that a decoder's buffer can be
    // freed first).
    Texture(std::string name, int width, int height, const uint8_t* rgba, bool srgb, bool hasAlpha, bool withMips = true);
    Texture(std::string name, int width, int height, const uint16_t* rgba, bool srgb, bool hasAlpha, bool withMips = true);
    void buildMipChain();

    int width() const { return levels_.empty() ? 0 : levels_[0].width; }
    int height() const { return levels_.empty() ? 0 : levels_[0].height; }
    int levelCount() const { return int(levels_.size()); }
    int levelWidth(int level) const { return levels_[size_t(level)].width; }
    int levelHeight(int level) const { return levels_[size_t(level)].height; }
    bool srgb() const { return srgb_; }
    bool hasAlpha() const { return hasAlpha_; }
    bool sixteenBit() const { return !texels16_.empty(); }
    // Bytes the texels of every level hold.
    size_t bytes() const { return texels8_.size() + 2 * texels16_.size(); }

    // Linear RGBA: trilinear between mip levels `lod` (0: the image itself; fractions blend two
    // levels), bilinear within a level, repeat wrap.
    Vec4 sample(Vec2 uv, float lod = 0.f) const;
    // The mip level for a footprint `uvFootprint` wide in uv units (Scene::uvFootprint):
    // log2 of the texels it spans (the ray-cone rule of "Texture Level of Detail Strategies for
    // Real-Time Ray Tracing", Akenine-Möller et al., with the texture's size split off so that
    // one footprint serves every texture of a material); 0 or below for a point.
    float lodOf(float uvFootprint) const;
    // Linear RGBA of texel (x, y) of a level, 0 ≤ x < levelWidth.
    Vec4 texel(int level, int x, int y) const;

    // The level-0 texel holding uv (repeat): the alpha test reads texels, not a filtered value, so
    // that both voxelizers and the ray tracer cut a surface along the same texel edges.
    int texelAt(Vec2 uv) const;
    // Alpha of level-0 texel `index` (texelAt's numbering): value / 255 (or / 65535); 1 without alpha.
    float alphaAt(int index) const;

private:
    struct Level {
        int width = 0, height = 0;
        size_t offset = 0;  // of its first texel in the texel array
    };
    void layOutLevels(int width, int height);
    template <class T>
    void buildMips(std::vector<T>& texels);
    Vec4 bilinear(int level, Vec2 uv) const;

    std::vector<Level> levels_;
    std::vector<uint8_t> texels8_;    // RGBA, every level in turn; empty for 16-bit images
    std::vector<uint16_t> texels16_;  // RGBA, every level in turn; empty for 8-bit images
    bool srgb_ = true, hasAlpha_ = false;
};

// sRGB's transfer function (IEC 61966-2-1), both ways, on [0, 1].
float srgbToLinear(float c);
float linearToSrgb(float c);

}  // namespace rs
