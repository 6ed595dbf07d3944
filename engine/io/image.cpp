#include "engine/io/image.h"

#include <cmath>
#include <cstring>

#include "engine/io/file_bytes.h"

namespace vtloc::io {

StoredImage read_image_file(const std::string& path) {
    std::vector<uint8_t> bytes = read_file_bytes(path);
    if (bytes.empty()) fail(path, "file is empty, not an image");
    return decode_image(bytes, path);
}

RgbImage load_tactile_image(const std::string& path) {
    const StoredImage raw = read_image_file(path);
    if (raw.width < kMinImageSide || raw.height < kMinImageSide)
        fail(path, "image is " + std::to_string(raw.width) + "x" + std::to_string(raw.height) +
                       " pixels; at least " + std::to_string(kMinImageSide) + "x" +
                       std::to_string(kMinImageSide) + " needed");
    // Grey (+ alpha) replicated, alpha dropped, 16 bits rounded to 8 (65535 -> 255).
    RgbImage out(raw.height, raw.width);
    const size_t n = size_t(raw.width) * size_t(raw.height);
    const int c = raw.channels;
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            const size_t s = i * size_t(c) + size_t(c < 3 ? 0 : k);
            out.pixels[i * 3 + size_t(k)] =
                raw.bits == 16 ? uint8_t(std::lround(raw.sample16(s) / 257.0)) : raw.data[s];
        }
    }
    return out;
}

DepthImage load_depth_image(const std::string& path) {
    const StoredImage raw = read_image_file(path);
    if (raw.channels != 1 || raw.bits != 16)
        fail(path, "a depth image must be a single-channel 16-bit PNG, got " + std::to_string(raw.channels) +
                       " channel(s) of " + std::to_string(raw.bits) + "-bit values");
    DepthImage out{raw.height, raw.width, std::vector<uint16_t>(size_t(raw.height) * size_t(raw.width))};
    std::memcpy(out.depth.data(), raw.data.data(), raw.data.size());
    return out;
}

MaskImage load_mask_image(const std::string& path) {
    const StoredImage raw = read_image_file(path);
    if (raw.channels != 1) fail(path, "a mask must be a single-channel image, got " + std::to_string(raw.channels) + " channels");
    MaskImage out{raw.height, raw.width, std::vector<uint8_t>(size_t(raw.height) * size_t(raw.width))};
    for (size_t i = 0; i < out.on.size(); ++i) out.on[i] = raw.bits == 16 ? raw.sample16(i) != 0 : raw.data[i] != 0;
    return out;
}

void save_png(const std::string& path, const RgbImage& image) {
    if (image.height <= 0 || image.width <= 0) fail(path, "cannot write an empty image");
    StoredImage im;
    im.height = image.height, im.width = image.width, im.channels = 3, im.bits = 8;
    im.data = image.pixels;
    const std::vector<uint8_t> png = encode_png(im, path);
    write_file_atomic(path, png.data(), png.size());
}

}  // namespace vtloc::io
