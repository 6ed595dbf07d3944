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
    const uint16_t* samples16() const { return reinterpret_cast<const uint16_t*>(data.data()); }
};

// Decodes PNG, JPEG or BMP bytes (chosen by their signature). Palette and
// sub-8-bit PNGs come out as 8-bit, a PNG's transparency colour as alpha;
// JPEG comes out grey or RGB. Throws vtloc::Error("<path>: <problem>").
StoredImage decode_image(const std::vector<uint8_t>& bytes, const std::string& path);

// A PNG of 1, 2, 3 or 4 channels at 8 or 16 bits; throws naming path when the
// image is empty or malformed.
std::vector<uint8_t> encode_png(const StoredImage& image, const std::string& path);

}  // namespace vtloc::io
