#pragma once
// Tactile frames, depth images and masks from PNG, JPEG or BMP files (engine/io/image_codec.h).
#include <cstdint>
#include <string>
#include <vector>

#include "engine/io/image_codec.h"

namespace vtloc::io {

// Row-major H x W x 3 uint8, channels in RGB order (SPEC section 1's T).
struct RgbImage {
    int height = 0, width = 0;
    std::vector<uint8_t> pixels;  // height * width * 3

    RgbImage() = default;
    RgbImage(int h, int w) : height(h), width(w), pixels(size_t(h) * size_t(w) * 3, 0) {}
    uint8_t* at(int y, int x) { return &pixels[(size_t(y) * size_t(width) + size_t(x)) * 3]; }
    const uint8_t* at(int y, int x) const { return &pixels[(size_t(y) * size_t(width) + size_t(x)) * 3]; }
};

// Smallest image the loader accepts; anything smaller is surely not a sensor frame.
inline constexpr int kMinImageSide = 8;

// Reads an image file as RGB. Grey images are replicated to three channels,
// alpha is dropped (not composited: what torchvision's ImageReadMode.RGB and
// PIL's convert("RGB") do, so weights_tools sees the same pixels), 16-bit
// images are scaled to 8 bits, and EXIF orientation is not applied (as in
// PIL). Throws vtloc::Error naming the file for a missing or unreadable file,
// a file that is not an image, an unsupported pixel type, or an image smaller
// than kMinImageSide on either side.
RgbImage load_tactile_image(const std::string& path);

// A depth camera's frame: one 16-bit value per pixel (0 = no measurement).
struct DepthImage {
    int height = 0, width = 0;
    std::vector<uint16_t> depth;  // row-major
};
// A single-channel 16-bit image (PNG), as stored; throws naming the file otherwise.
DepthImage load_depth_image(const std::string& path);

// An object mask: nonzero pixels (of an 8- or 16-bit single-channel image) are the object.
struct MaskImage {
    int height = 0, width = 0;
    std::vector<uint8_t> on;  // 0/1, row-major
};
MaskImage load_mask_image(const std::string& path);

// A PNG, JPEG or BMP file's pixels as stored, its header's size checked
// (at most 8192 a side) before decoding; throws naming the file.
StoredImage read_image_file(const std::string& path);

// Writes a PNG (lossless, so a frame survives a round trip bit for bit).
void save_png(const std::string& path, const RgbImage& image);

}  // namespace vtloc::io
