#include "engine/io/image.h"

#include <cmath>
#include <cstring>

#include "engine/io/file_bytes.h"

namespace vtloc::io {

namespace {

uint32_t be16(const uint8_t* p) { return uint32_t(p[0]) << 8 | p[1]; }
uint32_t be32(const uint8_t* p) { return be16(p) << 16 | be16(p + 2); }
uint32_t le32(const uint8_t* p) { return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24; }

// The largest side accepted: far above any tactile frame or depth camera, far
// below what would let a forged header allocate gigabytes.
constexpr uint32_t kMaxImageSide = 8192;

// Only PNG, JPEG and BMP are decoded, and their size is read from the header
// before any decoder allocates for it (when OpenCV decoded, a fuzzer led a
// ".png" with a DICOM body into a 2.6 GB allocation).
void check_format(const std::vector<uint8_t>& b, const std::string& path) {
    const size_t n = b.size();
    uint32_t w = 0, h = 0;
    if (n >= 24 && std::memcmp(b.data(), "\x89PNG\r\n\x1a\n", 8) == 0 && std::memcmp(&b[12], "IHDR", 4) == 0) {
        w = be32(&b[16]), h = be32(&b[20]);
    } else if (n >= 26 && b[0] == 'B' && b[1] == 'M') {
        w = le32(&b[18]);
        const int32_t sh = int32_t(le32(&b[22]));  // negative: rows stored top-down
        h = sh < 0 ? uint32_t(-int64_t(sh)) : uint32_t(sh);
    } else if (n >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) {
        for (size_t i = 2; i + 9 < n && !w;) {  // segments until a start-of-frame marker
            if (b[i] != 0xFF) fail(path, "JPEG data is corrupt (no marker where one belongs)");
            const uint8_t m = b[i + 1];
            if (m == 0xFF) { ++i; continue; }
            if (m == 0xDA || m == 0xD9) break;  // scan data or end before any frame header
            if (m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC) h = be16(&b[i + 5]), w = be16(&b[i + 7]);
            i += 2 + be16(&b[i + 2]);
        }
        if (!w || !h) fail(path, "JPEG data is corrupt (no frame header with the image size)");
    } else {
        fail(path, "not an image this engine reads (PNG, JPEG or BMP; other formats are refused)");
    }
    if (w == 0 || h == 0 || w > kMaxImageSide || h > kMaxImageSide)
        fail(path, "the image header says " + std::to_string(w) + "x" + std::to_string(h) + " pixels; at most " +
                       std::to_string(kMaxImageSide) + " a side is read");
}

}  // namespace

StoredImage read_image_file(const std::string& path) {
    std::vector<uint8_t> bytes = read_file_bytes(path);
    if (bytes.empty()) fail(path, "file is empty, not an image");
    check_format(bytes, path);
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
                raw.bits == 16 ? uint8_t(std::lround(raw.samples16()[s] / 257.0)) : raw.data[s];
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
    for (size_t i = 0; i < out.on.size(); ++i) out.on[i] = raw.bits == 16 ? raw.samples16()[i] != 0 : raw.data[i] != 0;
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
