// Tactile image loading. Fixtures are cv::Mats (BGR, as OpenCV holds them)
// written through engine/io's PNG writer, so a missing or doubled channel swap
// shows up; the JPEG is written with libjpeg here. PIL's own files and decodes
// are the oracle in tests/python (test_images.py).
#include <catch2/catch.hpp>
#include <cstdio>
#include <jpeglib.h>
#include <opencv2/core.hpp>

#include "engine/io/image.h"
#include "engine/io/image_mat.h"
#include "tests/io_test_util.h"

using namespace vtloc;
using namespace vtloc::io;
using vtloc::test::require_error;
using vtloc::test::temp_path;
using vtloc::test::write_temp;

namespace {

// 12 x 10 BGR image with distinct values per pixel; pixel (0, 0) is pure red.
cv::Mat bgr_fixture() {
    cv::Mat m(12, 10, CV_8UC3);
    for (int y = 0; y < m.rows; ++y)
        for (int x = 0; x < m.cols; ++x) m.at<cv::Vec3b>(y, x) = cv::Vec3b(uint8_t(x * 20), uint8_t(y * 20), uint8_t(100 + x + y));
    m.at<cv::Vec3b>(0, 0) = cv::Vec3b(0, 0, 255);
    return m;
}

// A baseline JPEG of an 8-bit BGR or grey Mat (libjpeg's defaults, quality 95).
std::string jpeg_bytes(const cv::Mat& m) {
    jpeg_compress_struct c;
    jpeg_error_mgr err;
    c.err = jpeg_std_error(&err);
    jpeg_create_compress(&c);
    unsigned char* out = nullptr;
    unsigned long size = 0;
    jpeg_mem_dest(&c, &out, &size);
    c.image_width = JDIMENSION(m.cols), c.image_height = JDIMENSION(m.rows);
    c.input_components = m.channels();
    c.in_color_space = m.channels() == 1 ? JCS_GRAYSCALE : JCS_EXT_BGR;
    jpeg_set_defaults(&c);
    jpeg_set_quality(&c, 95, TRUE);
    jpeg_start_compress(&c, TRUE);
    while (c.next_scanline < c.image_height) {
        JSAMPROW row = const_cast<JSAMPROW>(m.ptr(int(c.next_scanline)));
        jpeg_write_scanlines(&c, &row, 1);
    }
    jpeg_finish_compress(&c);
    jpeg_destroy_compress(&c);
    std::string bytes(reinterpret_cast<char*>(out), size);
    std::free(out);
    return bytes;
}

}  // namespace

TEST_CASE("a PNG of a BGR Mat loads as RGB", "[io]") {
    cv::Mat bgr = bgr_fixture();
    std::string path = temp_path("rgb_order.png");
    write_png(path, bgr);
    RgbImage img = load_tactile_image(path);
    REQUIRE(img.height == 12);
    REQUIRE(img.width == 10);
    CHECK(img.at(0, 0)[0] == 255);  // red first
    CHECK(img.at(0, 0)[1] == 0);
    CHECK(img.at(0, 0)[2] == 0);
    for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 10; ++x) {
            cv::Vec3b b = bgr.at<cv::Vec3b>(y, x);
            REQUIRE(img.at(y, x)[0] == b[2]);
            REQUIRE(img.at(y, x)[1] == b[1]);
            REQUIRE(img.at(y, x)[2] == b[0]);
        }
    // save_png round trip, bit for bit.
    std::string again = temp_path("rgb_again.png");
    save_png(again, img);
    CHECK(load_tactile_image(again).pixels == img.pixels);
    CHECK(read_mat(again).at<cv::Vec3b>(0, 0) == cv::Vec3b(0, 0, 255));
}

TEST_CASE("grey, alpha, 16-bit, JPEG and BMP images", "[io]") {
    cv::Mat grey(9, 11, CV_8UC1, cv::Scalar(77));
    write_png(temp_path("grey.png"), grey);
    RgbImage g = load_tactile_image(temp_path("grey.png"));
    CHECK(g.width == 11);
    CHECK((g.at(3, 4)[0] == 77 && g.at(3, 4)[1] == 77 && g.at(3, 4)[2] == 77));

    cv::Mat bgra(8, 8, CV_8UC4, cv::Scalar(10, 20, 30, 0));  // fully transparent: dropped, not composited
    write_png(temp_path("alpha.png"), bgra);
    RgbImage a = load_tactile_image(temp_path("alpha.png"));
    CHECK((a.at(7, 7)[0] == 30 && a.at(7, 7)[1] == 20 && a.at(7, 7)[2] == 10));

    // Samples whose high and low bytes differ, so that a swap of red and blue that
    // moved single bytes instead of whole samples would show.
    cv::Mat deep(8, 8, CV_16UC3, cv::Scalar(0x0102, 65535, 0x1234));
    write_png(temp_path("deep.png"), deep);
    RgbImage d = load_tactile_image(temp_path("deep.png"));
    CHECK((d.at(0, 0)[0] == 18 && d.at(0, 0)[1] == 255 && d.at(0, 0)[2] == 1));  // 0x1234 / 257 = 18.1
    const cv::Mat deep_again = read_mat(temp_path("deep.png"));  // as stored: 16 bits, BGR
    REQUIRE(deep_again.type() == CV_16UC3);
    CHECK(cv::norm(deep_again, deep, cv::NORM_INF) == 0);
    cv::Mat deep4(3, 5, CV_16UC4, cv::Scalar(0x0102, 0x0304, 0x0506, 0x0708));
    write_png(temp_path("deep4.png"), deep4);
    const StoredImage stored4 = read_image_file(temp_path("deep4.png"));  // RGBA order in the file
    REQUIRE((stored4.channels == 4 && stored4.bits == 16));
    CHECK((stored4.sample16(0) == 0x0506 && stored4.sample16(1) == 0x0304 && stored4.sample16(2) == 0x0102 &&
           stored4.sample16(3) == 0x0708));
    CHECK(cv::norm(read_mat(temp_path("deep4.png")), deep4, cv::NORM_INF) == 0);
    {
        cv::Mat depth(5, 7, CV_16UC1);
        for (int i = 0; i < 35; ++i) depth.at<uint16_t>(i / 7, i % 7) = uint16_t(i * 1871 + 3);  // high and low bytes differ
        write_png(temp_path("depth16.png"), depth);
        const DepthImage dd = load_depth_image(temp_path("depth16.png"));
        REQUIRE((dd.width == 7 && dd.height == 5));
        for (int i = 0; i < 35; ++i) REQUIRE(dd.depth[size_t(i)] == uint16_t(i * 1871 + 3));
    }

    cv::Mat flat(16, 16, CV_8UC3, cv::Scalar(40, 120, 200));
    const std::string jpg = jpeg_bytes(flat);
    RgbImage j = load_tactile_image(write_temp("flat.jpg", jpg));
    CHECK(std::abs(int(j.at(8, 8)[0]) - 200) <= 3);  // lossy: a flat colour within 3 levels
    CHECK(std::abs(int(j.at(8, 8)[2]) - 40) <= 3);
    // Data that ends early would be finished in grey: an error, not a picture.
    require_error([&] { load_tactile_image(write_temp("cut.jpg", jpg.substr(0, jpg.size() / 2))); },
                  {"cut.jpg", "corrupt or truncated"});
    const cv::Mat grey_jpeg = read_mat(write_temp("grey.jpg", jpeg_bytes(grey)));
    CHECK((grey_jpeg.channels() == 1 && std::abs(int(grey_jpeg.at<uint8_t>(4, 5)) - 77) <= 1));

    // A bottom-up 24-bit BMP, 9 x 8 (rows padded to 28 bytes), written by hand.
    std::string bmp = "BM";
    auto le = [&](uint32_t v, int n) { for (int k = 0; k < n; ++k) bmp += char((v >> (8 * k)) & 0xFF); };
    le(54 + 28 * 8, 4), le(0, 4), le(54, 4);                      // file header
    le(40, 4), le(9, 4), le(8, 4), le(1, 2), le(24, 2), le(0, 4);  // info header: 9 x 8, 24 bits, no compression
    le(28 * 8, 4), le(2835, 4), le(2835, 4), le(0, 4), le(0, 4);
    for (int row = 0; row < 8; ++row) {  // stored bottom-up: the last row first
        const int y = 7 - row;
        for (int x = 0; x < 9; ++x) bmp += char(x * 10), bmp += char(y * 10), bmp += char(200);  // B, G, R
        bmp += std::string(1, '\0');
    }
    const RgbImage b = load_tactile_image(write_temp("frame.bmp", bmp));
    REQUIRE((b.width == 9 && b.height == 8));
    CHECK((b.at(0, 0)[0] == 200 && b.at(0, 0)[1] == 0 && b.at(0, 0)[2] == 0));
    CHECK((b.at(7, 8)[0] == 200 && b.at(7, 8)[1] == 70 && b.at(7, 8)[2] == 80));
}

TEST_CASE("image errors name the file and the problem", "[io]") {
    require_error([] { load_tactile_image(temp_path("no_such.png")); }, {"no_such.png", "no such file"});
    require_error([] { load_tactile_image(vtloc::test::temp_path("")); }, {"is a directory"});
    require_error([] { load_tactile_image(write_temp("empty.png", "")); }, {"empty.png", "empty"});
    require_error([] { load_tactile_image(write_temp("text.png", "hello, I am not a picture\n")); },
                  {"text.png", "not an image"});
    // Fuzzer finding (tests/fuzz, fuzz_image), from when OpenCV decoded by content and read
    // DICOM through GDCM: a ".png" with a DICOM body asked for 2.6 GB. Only PNG, JPEG and BMP
    // reach a decoder, and a header claiming a huge image is refused before it.
    std::string dicom(128, '\0');
    dicom += "DICM";
    require_error([&] { load_tactile_image(write_temp("dicom.png", dicom)); }, {"dicom.png", "not an image this engine reads"});
    {
        cv::Mat tiny(9, 9, CV_8UC3, cv::Scalar(5, 6, 7));
        std::vector<uint8_t> png = encode_png(tiny, "tiny.png");
        png[16] = 0x7F;  // IHDR width -> ~2.1 billion
        require_error([&] { load_tactile_image(write_temp("huge.png", std::string(png.begin(), png.end()))); },
                      {"huge.png", "the image header says", "at most 8192 a side"});
        const std::string tif("II*\0\x08\0\0\0\0\0", 10);  // a little-endian TIFF header
        require_error([&] { load_tactile_image(write_temp("frame.tiff", tif)); },
                      {"frame.tiff", "PNG, JPEG or BMP"});
    }
    cv::Mat small(4, 6, CV_8UC3, cv::Scalar(1, 2, 3));
    write_png(temp_path("small.png"), small);
    require_error([] { load_tactile_image(temp_path("small.png")); },
                  {"small.png", "image is 6x4 pixels; at least 8x8 needed"});
    {
        std::vector<uint8_t> png = encode_png(bgr_fixture(), "fixture.png");
        std::string cut(png.begin(), png.begin() + long(png.size() / 2));
        require_error([&] { load_tactile_image(write_temp("cut.png", cut)); },
                      {"cut.png", "corrupt or truncated"});
    }
}
