#pragma once
// cv::Mat in and out of image files through engine/io's own codecs, for the
// code that draws with OpenCV (plots, pictures, dataset frames). Mats are in
// OpenCV's channel order (BGR, BGRA), as cv::imread and cv::imwrite use them.
// Header-only: vtloc_io itself keeps OpenCV out of its interface.
#include <cstring>
#include <opencv2/core.hpp>
#include <string>

#include "engine/io/file_bytes.h"
#include "engine/io/image.h"

namespace vtloc::io {

inline StoredImage stored_from_mat(const cv::Mat& m, const std::string& path) {
    if (m.empty()) fail(path, "cannot write an empty image");
    if (m.depth() != CV_8U && m.depth() != CV_16U) fail(path, "only 8- and 16-bit images are written");
    StoredImage im;
    im.height = m.rows, im.width = m.cols, im.channels = m.channels(), im.bits = m.depth() == CV_16U ? 16 : 8;
    if (im.channels > 4) fail(path, "a PNG holds at most 4 channels");
    im.data.resize(im.row_bytes() * size_t(im.height));
    for (int y = 0; y < m.rows; ++y) std::memcpy(&im.data[size_t(y) * im.row_bytes()], m.ptr(y), im.row_bytes());
    im.swap_red_blue();
    return im;
}

// A PNG of the Mat (8- or 16-bit, 1-4 channels); throws naming path.
inline std::vector<uint8_t> encode_png(const cv::Mat& m, const std::string& path) {
    return encode_png(stored_from_mat(m, path), path);
}

// Writes the Mat as a PNG at path (atomically); throws naming path.
inline void write_png(const std::string& path, const cv::Mat& m) {
    const std::vector<uint8_t> png = encode_png(m, path);
    vtloc::write_file_atomic(path, png.data(), png.size());
}

// The file's pixels as stored, as cv::imread(path, cv::IMREAD_UNCHANGED) gives them.
inline cv::Mat read_mat(const std::string& path) {
    StoredImage im = read_image_file(path);
    cv::Mat m(im.height, im.width, CV_MAKETYPE(im.bits == 16 ? CV_16U : CV_8U, im.channels));
    im.swap_red_blue();
    for (int y = 0; y < m.rows; ++y) std::memcpy(m.ptr(y), &im.data[size_t(y) * im.row_bytes()], im.row_bytes());
    return m;
}

}  // namespace vtloc::io
