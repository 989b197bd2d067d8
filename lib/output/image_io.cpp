// OpenEXR and PNG (image_io.h). The only file that includes OpenEXR.
#include "output/image_io.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfThreading.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "core/error.h"

namespace rs {

void writeExrTo(const std::string& tmp, const std::string& path, const Film& film, const ImageAttributes& attributes,
                int threads, const std::string& blenderLayer) {
    // Blender's multilayer naming: <view layer>.<Pass>.<channel>, Combined with an alpha of 1 and
    // the normal as a vector in Blender's axes (glTF +Y up is Blender's +Z up).
    const bool blender = !blenderLayer.empty();
    std::vector<Vec3> beauty = film.beautyImage();
    std::vector<Vec3> normal = film.normal;
    if (blender)
        for (Vec3& n : normal) n = Vec3(n.x, -n.z, n.y);
    const std::vector<float> opaque(blender ? film.pixelCount() : 0, 1.f);
    struct Group {
        std::string prefix;
        const char* channels;
        const float* data;
        size_t stride;  // floats from one pixel to the next
    };
    auto pass = [&](const char* own, std::string name) { return blender ? blenderLayer + "." + name + "." : std::string(own); };
    std::vector<Group> groups = {{pass("", "Combined"), "RGB", &beauty[0].x, 3}};
    if (blender) groups.push_back({pass("", "Combined"), "A", opaque.data(), 1});
    for (int l = 0; l < kLayerCount; ++l) {
        std::string own = std::string(layerName(l)) + ".", name = layerName(l);
        name[0] = char(std::toupper(static_cast<unsigned char>(name[0])));
        groups.push_back({pass(own.c_str(), name), "RGB", &film.layers[l][0].x, 3});
    }
    groups.push_back({pass("albedo.", "Albedo"), "RGB", &film.albedo[0].x, 3});
    groups.push_back({pass("normal.", "Normal"), blender ? "XYZ" : "RGB", &normal[0].x, 3});

    try {
        Imf::Header header(film.width, film.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        for (const auto& [key, value] : attributes) header.insert(key, Imf::StringAttribute(value));
        Imf::FrameBuffer fb;
        for (const Group& g : groups) {
            for (int c = 0; g.channels[c]; ++c) {
                std::string name = g.prefix + g.channels[c];
                header.channels().insert(name, Imf::Channel(Imf::FLOAT));
                char* base = const_cast<char*>(reinterpret_cast<const char*>(g.data + c));
                fb.insert(name, Imf::Slice(Imf::FLOAT, base, g.stride * sizeof(float), g.stride * sizeof(float) * size_t(film.width)));
            }
        }
        // Compressing is most of the write (0.4 s of the glossy box's 500×500 on one core);
        // OpenEXR's pool takes the blocks, the file keeps their order.
        threads = std::max(1, threads);
        if (Imf::globalThreadCount() != threads) Imf::setGlobalThreadCount(threads);
        Imf::OutputFile file(tmp.c_str(), header, threads);
        file.setFrameBuffer(fb);
        file.writePixels(film.height);
    } catch (const std::exception& e) {
        std::error_code ec;
        std::filesystem::remove(tmp, ec);
        throw Error(ErrorKind::Io, path + ": cannot write EXR: " + e.what());
    }
}

ExrImage readExr(const std::string& path) {
    ExrImage img;
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header& h = file.header();
        Imath::Box2i dw = h.dataWindow();
        img.width = dw.max.x - dw.min.x + 1;
        img.height = dw.max.y - dw.min.y + 1;
        Imf::FrameBuffer fb;
        size_t n = size_t(img.width) * img.height;
        for (auto it = h.channels().begin(); it != h.channels().end(); ++it) {
            std::vector<float>& v = img.channels[it.name()];
            v.assign(n, 0.f);
            char* base = reinterpret_cast<char*>(v.data()) - (size_t(dw.min.x) + size_t(dw.min.y) * img.width) * sizeof(float);
            fb.insert(it.name(), Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * img.width));
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        for (auto it = h.begin(); it != h.end(); ++it)
            if (auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute())) img.attributes[it.name()] = s->value();
    } catch (const std::exception& e) {
        throw Error(ErrorKind::Io, path + ": cannot read EXR: " + e.what());
    }
    return img;
}

std::vector<Vec3> ExrImage::rgb(const std::string& prefix) const {
    std::vector<Vec3> out(size_t(width) * height);
    const char* comp[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) {
        auto it = channels.find(prefix + comp[c]);
        if (it == channels.end()) throw Error(ErrorKind::Io, "EXR has no channel " + prefix + comp[c]);
        for (size_t i = 0; i < out.size(); ++i) out[i][c] = it->second[i];
    }
    return out;
}

// -- PNG ---------------------------------------------------------------------------------

namespace {

void appendBigEndian(std::string& s, uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) s.push_back(char((v >> shift) & 0xff));
}

void appendChunk(std::string& out, const char* type, const std::string& data) {
    appendBigEndian(out, uint32_t(data.size()));
    std::string body = std::string(type, 4) + data;
    out += body;
    appendBigEndian(out, uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(body.data()), uInt(body.size()))));
}

uint8_t encodeSrgb(float linear) {
    float c = std::clamp(linear, 0.f, 1.f);
    c = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.f / 2.4f) - 0.055f;
    return uint8_t(std::lround(c * 255.f));
}

}  // namespace

std::string encodePng(const Film& film, float exposureStops) {
    float gain = std::exp2(exposureStops);
    std::string raw;
    raw.reserve(film.pixelCount() * 3 + film.height);
    for (int y = 0; y < film.height; ++y) {
        raw.push_back(0);  // filter: none
        for (int x = 0; x < film.width; ++x) {
            Vec3 c = film.beauty(size_t(y) * film.width + x) * gain;
            for (int k = 0; k < 3; ++k) raw.push_back(char(encodeSrgb(c[k])));
        }
    }
    uLongf size = compressBound(uLong(raw.size()));
    std::string packed(size, '\0');
    if (compress2(reinterpret_cast<Bytef*>(packed.data()), &size, reinterpret_cast<const Bytef*>(raw.data()),
                  uLong(raw.size()), 6) != Z_OK)
        throw Error(ErrorKind::Internal, "PNG compression failed");
    packed.resize(size);

    std::string ihdr;
    appendBigEndian(ihdr, uint32_t(film.width));
    appendBigEndian(ihdr, uint32_t(film.height));
    ihdr += std::string("\x08\x02\x00\x00\x00", 5);  // 8-bit RGB, deflate, no filter, no interlace
    std::string out("\x89PNG\r\n\x1a\n", 8);
    appendChunk(out, "IHDR", ihdr);
    appendChunk(out, "IDAT", packed);
    appendChunk(out, "IEND", "");
    return out;
}


}  // namespace rs
