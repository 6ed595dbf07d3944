#pragma once
// PNG, JPEG and BMP in memory, with libpng, libjpeg-turbo (the decoders OpenCV
// and PIL use, so every pixel matches what weights_tools reads) and stb_image
// for BMP. Not OpenCV's imgcodecs: on Debian it links GDAL and ~120 libraries,
// 0.12 s at every start of every program that links it.
#include <cstdint>
#include <string>
#include <vector>

namespace vtloc::io {

// Pixels as a file stores them. Channels: 1 grey, 2 grey + alpha, 3 RGB,
// 4 RGBA (RGB order, not OpenCV's BGR). 16-bit samples are in host byte order.
struct StoredImage {
    int height = 0, width = 0, channels = 0, bits = 8;
    std::vector<uint8_t> data;  // rows top-down, height * width * channels * bits / 8 bytes

    size_t row_bytes() const { return size_t(width) * size_t(channels) * size_t(bits / 8); }
    // Sample i of a 16-bit image (copied out: the bytes need not be aligned for uint16_t).
    uint16_t sample16(size_t i) const;
    // Swaps the first and third channel of 3- and 4-channel pixels (RGB <-> BGR), at 8 or 16 bits.
    void swap_red_blue();
};

// Decodes PNG, JPEG or BMP bytes (chosen by their signature); the header's size
// is checked (at most 8192 a side) before any decoder allocates for it. Palette
// and sub-8-bit PNGs come out as 8-bit, a PNG's transparency colour as alpha;
// JPEG comes out grey or RGB. Throws vtloc::Error("<path>: <problem>").
StoredImage decode_image(const std::vector<uint8_t>& bytes, const std::string& path);

// A PNG of 1, 2, 3 or 4 channels at 8 or 16 bits; throws naming path when the
// image is empty or malformed.
std::vector<uint8_t> encode_png(const StoredImage& image, const std::string& path);

}  // namespace vtloc::io
