#include "engine/io/image.h"

#include <cstring>

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "engine/io/file_bytes.h"

namespace vtloc::io {

namespace {

// OpenCV logs its own warnings for undecodable data; our Error says it once.
void quiet_opencv() {
    static const bool once = [] {
        cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_ERROR);
        return true;
    }();
    (void)once;
}

uint32_t be16(const uint8_t* p) { return uint32_t(p[0]) << 8 | p[1]; }
uint32_t be32(const uint8_t* p) { return be16(p) << 16 | be16(p + 2); }
uint32_t le32(const uint8_t* p) { return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24; }

// The largest side accepted: far above any tactile frame or depth camera, far
// below what would let a forged header allocate gigabytes.
constexpr uint32_t kMaxImageSide = 8192;

// OpenCV picks a decoder by content, and Debian's also reads DICOM, NITF and
// more through GDCM and GDAL (a fuzzer led a ".png" into a 2.6 GB DICOM
// allocation): only PNG, JPEG and BMP reach it, with their size checked first.
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

// Decodes a PNG, JPEG or BMP file as stored (depth, channels), or throws naming the file.
cv::Mat decode(const std::string& path) {
    quiet_opencv();
    std::vector<uint8_t> bytes = read_file_bytes(path);
    if (bytes.empty()) fail(path, "file is empty, not an image");
    check_format(bytes, path);
    cv::Mat raw;
    try {
        // IMREAD_UNCHANGED keeps grey/alpha/16-bit visible to us and skips EXIF rotation.
        raw = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception& e) {
        fail(path, "cannot decode image (" + e.msg + ")");
    }
    if (raw.empty()) {
        // imdecode cannot tell us why; the signature check says whether any codec claims the bytes.
        bool known = false;
        try {
            known = cv::haveImageReader(path);
        } catch (const cv::Exception&) {
        }
        fail(path, known ? "image data is corrupt or truncated" : "not an image (no image format recognised)");
    }
    return raw;
}

}  // namespace

RgbImage load_tactile_image(const std::string& path) {
    cv::Mat raw = decode(path);
    if (raw.depth() == CV_16U) {
        raw.convertTo(raw, CV_8U, 1.0 / 257.0);  // 65535 -> 255
    } else if (raw.depth() != CV_8U) {
        fail(path, "unsupported pixel type (only 8- and 16-bit integer images are read)");
    }
    cv::Mat rgb;
    switch (raw.channels()) {
        case 1: cv::cvtColor(raw, rgb, cv::COLOR_GRAY2RGB); break;
        case 3: cv::cvtColor(raw, rgb, cv::COLOR_BGR2RGB); break;
        case 4: cv::cvtColor(raw, rgb, cv::COLOR_BGRA2RGB); break;
        default: fail(path, "unsupported image with " + std::to_string(raw.channels()) + " channels");
    }
    if (rgb.rows < kMinImageSide || rgb.cols < kMinImageSide)
        fail(path, "image is " + std::to_string(rgb.cols) + "x" + std::to_string(rgb.rows) +
                       " pixels; at least " + std::to_string(kMinImageSide) + "x" +
                       std::to_string(kMinImageSide) + " needed");
    RgbImage out(rgb.rows, rgb.cols);
    for (int y = 0; y < rgb.rows; ++y)
        std::memcpy(out.at(y, 0), rgb.ptr<uint8_t>(y), size_t(rgb.cols) * 3);
    return out;
}

DepthImage load_depth_image(const std::string& path) {
    cv::Mat raw = decode(path);
    if (raw.channels() != 1 || raw.depth() != CV_16U)
        fail(path, "a depth image must be a single-channel 16-bit PNG, got " + std::to_string(raw.channels()) +
                       " channel(s) of " + (raw.depth() == CV_8U ? "8" : raw.depth() == CV_16U ? "16" : "other") +
                       "-bit values");
    DepthImage out{raw.rows, raw.cols, std::vector<uint16_t>(size_t(raw.rows) * size_t(raw.cols))};
    for (int y = 0; y < raw.rows; ++y)
        std::memcpy(&out.depth[size_t(y) * size_t(raw.cols)], raw.ptr<uint16_t>(y), size_t(raw.cols) * 2);
    return out;
}

MaskImage load_mask_image(const std::string& path) {
    cv::Mat raw = decode(path);
    if (raw.channels() != 1) fail(path, "a mask must be a single-channel image, got " + std::to_string(raw.channels()) + " channels");
    MaskImage out{raw.rows, raw.cols, std::vector<uint8_t>(size_t(raw.rows) * size_t(raw.cols))};
    for (int y = 0; y < raw.rows; ++y)
        for (int x = 0; x < raw.cols; ++x)
            out.on[size_t(y) * size_t(raw.cols) + size_t(x)] =
                raw.depth() == CV_16U ? raw.at<uint16_t>(y, x) != 0 : raw.depth() == CV_8U ? raw.at<uint8_t>(y, x) != 0 : 0;
    if (raw.depth() != CV_8U && raw.depth() != CV_16U) fail(path, "a mask must hold 8- or 16-bit integers");
    return out;
}

void save_png(const std::string& path, const RgbImage& image) {
    quiet_opencv();
    if (image.height <= 0 || image.width <= 0) fail(path, "cannot write an empty image");
    cv::Mat rgb(image.height, image.width, CV_8UC3, const_cast<uint8_t*>(image.pixels.data()));
    cv::Mat bgr;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    std::vector<uint8_t> png;
    if (!cv::imencode(".png", bgr, png)) fail(path, "PNG encoding failed");
    write_file_atomic(path, png.data(), png.size());
}

}  // namespace vtloc::io
