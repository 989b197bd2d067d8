// The glTF loader's images (gltf_loader.h): tinygltf hands over each image's encoded bytes
// while it parses the file; once the materials have said which textures they need, the images
// are decoded by stb_image (PNG, JPEG and the rest it reads; 16-bit PNGs stay 16-bit) in
// parallel, one image a task, each straight into its Texture(s) and its encoded and decoded
// intermediates freed as soon as they are converted.
#include <stb_image.h>

#include <algorithm>
#include <climits>
#include <exception>
#include <memory>

#include "core/parallel.h"
#include "scene/gltf_loader.h"

namespace rs::gltf {

bool GltfLoader::keepEncodedImage(tinygltf::Image* image, int, std::string*, std::string*, int, int,
                                  const unsigned char* bytes, int size, void*) {
    // An image in a bufferView is read from its buffer when it is decoded: no copy.
    if (image->bufferView < 0 && size > 0) image->image.assign(bytes, bytes + size);
    image->as_is = true;
    return true;
}

void GltfLoader::decodeImages() {
    // One task an image, with the textures made of it (sRGB, linear or both), in image order.
    struct Task {
        int image;
        int srgbTexture = -1, linearTexture = -1;
    };
    std::vector<Task> tasks;
    for (const auto& [key, texture] : textureOfImage_) {
        if (tasks.empty() || tasks.back().image != key.first) tasks.push_back({key.first});
        (key.second ? tasks.back().srgbTexture : tasks.back().linearTexture) = texture;
    }
    if (!tasks.empty()) {
        // An image in flight holds its decoder's output beside its texture (then the level above
        // in floats while the mips are made): no more images at once than hold a third of all
        // the images' decoded bytes, whatever the thread count (at least one).
        size_t total = 0, largest = 0;
        for (const Task& t : tasks) {
            const size_t b = decodedBytes(t.image);
            total += b;
            largest = std::max(largest, b);
        }
        int threads = std::min(threads_ > 0 ? threads_ : ThreadPool::hardwareThreads(), int(tasks.size()));
        if (largest > 0) threads = std::clamp(int(total / 3 / largest), 1, threads);
        // Every task runs; the error reported is the first image's, whatever the thread count.
        std::vector<std::exception_ptr> errors(tasks.size());
        ThreadPool pool(threads);
        pool.parallelFor(int64_t(tasks.size()), 1, [&](int64_t begin, int64_t end, int) {
            for (int64_t i = begin; i < end; ++i) {
                try {
                    decodeImage(tasks[size_t(i)].image, tasks[size_t(i)].srgbTexture, tasks[size_t(i)].linearTexture);
                } catch (...) {
                    errors[size_t(i)] = std::current_exception();
                }
            }
        });
        for (const std::exception_ptr& e : errors)
            if (e) std::rethrow_exception(e);
    }
    // Images no texture uses are not decoded; their bytes go too.
    for (tinygltf::Image& img : model_.images) std::vector<unsigned char>().swap(img.image);
}

std::pair<const unsigned char*, size_t> GltfLoader::encodedBytes(const tinygltf::Image& img, const std::string& where) const {
    // The file's bytes (kept by keepEncodedImage) or the bufferView's.
    const unsigned char* bytes = img.image.data();
    size_t size = img.image.size();
    if (img.bufferView >= 0) {
        if (img.bufferView >= int(model_.bufferViews.size())) fail(where + ": bufferView " + std::to_string(img.bufferView) + " does not exist");
        const tinygltf::BufferView& view = model_.bufferViews[size_t(img.bufferView)];
        if (view.buffer < 0 || view.buffer >= int(model_.buffers.size()) ||
            view.byteOffset + view.byteLength > model_.buffers[size_t(view.buffer)].data.size())
            fail(where + ": bufferView " + std::to_string(img.bufferView) + " lies outside its buffer");
        bytes = model_.buffers[size_t(view.buffer)].data.data() + view.byteOffset;
        size = view.byteLength;
    }
    if (size == 0) fail(where + " has zero size");
    if (size > size_t(INT_MAX)) fail(where + " is larger than 2 GB");
    return {bytes, size};
}

size_t GltfLoader::decodedBytes(int index) const {
    try {
        const auto [bytes, size] = encodedBytes(model_.images[size_t(index)], "");
        int width = 0, height = 0, channels = 0;
        if (!stbi_info_from_memory(bytes, int(size), &width, &height, &channels)) return 0;
        return size_t(std::max(width, 0)) * size_t(std::max(height, 0)) * 4 * (stbi_is_16_bit_from_memory(bytes, int(size)) ? 2 : 1);
    } catch (const Error&) {
        return 0;  // decodeImage reports it
    }
}

void GltfLoader::decodeImage(int index, int srgbTexture, int linearTexture) {
    tinygltf::Image& img = model_.images[size_t(index)];
    const std::string where = scene_.textures[size_t(srgbTexture >= 0 ? srgbTexture : linearTexture)].name;

    const auto [bytes, size] = encodedBytes(img, where);

    // Decode to RGBA (grey and grey+alpha expanded), 8 or 16 bits as the file has it.
    int width = 0, height = 0, channels = 0;
    if (!stbi_info_from_memory(bytes, int(size), &width, &height, &channels))
        fail(where + " is not an image that can be read (" + stbi_failure_reason() + ")");
    if (width <= 0 || height <= 0) fail(where + " has zero size");
    if (size_t(width) * size_t(height) > (size_t(1) << 28)) fail(where + " has more than 2^28 texels");
    const bool sixteen = stbi_is_16_bit_from_memory(bytes, int(size)) != 0;
    std::unique_ptr<void, void (*)(void*)> pixels(
        sixteen ? static_cast<void*>(stbi_load_16_from_memory(bytes, int(size), &width, &height, &channels, 4))
                : static_cast<void*>(stbi_load_from_memory(bytes, int(size), &width, &height, &channels, 4)),
        &stbi_image_free);
    if (!pixels) fail(where + " cannot be decoded: " + stbi_failure_reason() + " (a truncated or corrupt file?)");
    std::vector<unsigned char>().swap(img.image);

    // Level 0 of each texture, then the decoder's buffer goes, then the mip chains.
    const bool alpha = channels == 2 || channels == 4;
    auto build = [&](bool srgb) {
        return sixteen ? Texture(where, width, height, static_cast<const uint16_t*>(pixels.get()), srgb, alpha, false)
                       : Texture(where, width, height, static_cast<const uint8_t*>(pixels.get()), srgb, alpha, false);
    };
    if (srgbTexture >= 0) scene_.textures[size_t(srgbTexture)] = build(true);
    if (linearTexture >= 0) scene_.textures[size_t(linearTexture)] = build(false);
    pixels.reset();
    for (int t : {srgbTexture, linearTexture})
        if (t >= 0) scene_.textures[size_t(t)].buildMipChain();
}

}  // namespace rs::gltf
