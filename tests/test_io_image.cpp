// Tactile image loading: fixtures are written with OpenCV directly (BGR, as
// OpenCV stores them), so a missing or doubled channel swap shows up.
#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "engine/io/image.h"
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

}  // namespace

TEST_CASE("PNG written by OpenCV loads as RGB", "[io]") {
    cv::Mat bgr = bgr_fixture();
    std::string path = temp_path("rgb_order.png");
    REQUIRE(cv::imwrite(path, bgr));
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
    CHECK(cv::imread(again).at<cv::Vec3b>(0, 0) == cv::Vec3b(0, 0, 255));
}

TEST_CASE("grey, alpha, 16-bit and JPEG images", "[io]") {
    cv::Mat grey(9, 11, CV_8UC1, cv::Scalar(77));
    REQUIRE(cv::imwrite(temp_path("grey.png"), grey));
    RgbImage g = load_tactile_image(temp_path("grey.png"));
    CHECK(g.width == 11);
    CHECK((g.at(3, 4)[0] == 77 && g.at(3, 4)[1] == 77 && g.at(3, 4)[2] == 77));

    cv::Mat bgra(8, 8, CV_8UC4, cv::Scalar(10, 20, 30, 0));  // fully transparent: dropped, not composited
    REQUIRE(cv::imwrite(temp_path("alpha.png"), bgra));
    RgbImage a = load_tactile_image(temp_path("alpha.png"));
    CHECK((a.at(7, 7)[0] == 30 && a.at(7, 7)[1] == 20 && a.at(7, 7)[2] == 10));

    cv::Mat deep(8, 8, CV_16UC3, cv::Scalar(0, 65535, 257 * 100));
    REQUIRE(cv::imwrite(temp_path("deep.png"), deep));
    RgbImage d = load_tactile_image(temp_path("deep.png"));
    CHECK((d.at(0, 0)[0] == 100 && d.at(0, 0)[1] == 255 && d.at(0, 0)[2] == 0));

    cv::Mat flat(16, 16, CV_8UC3, cv::Scalar(40, 120, 200));
    REQUIRE(cv::imwrite(temp_path("flat.jpg"), flat));
    RgbImage j = load_tactile_image(temp_path("flat.jpg"));
    CHECK(std::abs(int(j.at(8, 8)[0]) - 200) <= 3);
    CHECK(std::abs(int(j.at(8, 8)[2]) - 40) <= 3);
}

TEST_CASE("image errors name the file and the problem", "[io]") {
    require_error([] { load_tactile_image(temp_path("no_such.png")); }, {"no_such.png", "no such file"});
    require_error([] { load_tactile_image(vtloc::test::temp_path("")); }, {"is a directory"});
    require_error([] { load_tactile_image(write_temp("empty.png", "")); }, {"empty.png", "empty"});
    require_error([] { load_tactile_image(write_temp("text.png", "hello, I am not a picture\n")); },
                  {"text.png", "not an image"});
    // Fuzzer finding (tests/fuzz, fuzz_image): OpenCV decodes by content, and Debian's reads
    // DICOM through GDCM; a ".png" with a DICOM body asked for 2.6 GB. Only PNG, JPEG and BMP
    // reach the decoder, and a header claiming a huge image is refused before it.
    std::string dicom(128, '\0');
    dicom += "DICM";
    require_error([&] { load_tactile_image(write_temp("dicom.png", dicom)); }, {"dicom.png", "not an image this engine reads"});
    {
        cv::Mat tiny(9, 9, CV_8UC3, cv::Scalar(5, 6, 7));
        std::vector<uint8_t> png;
        REQUIRE(cv::imencode(".png", tiny, png));
        png[16] = 0x7F;  // IHDR width -> ~2.1 billion
        require_error([&] { load_tactile_image(write_temp("huge.png", std::string(png.begin(), png.end()))); },
                      {"huge.png", "the image header says", "at most 8192 a side"});
        std::vector<uint8_t> tif;
        REQUIRE(cv::imencode(".tiff", tiny, tif));
        require_error([&] { load_tactile_image(write_temp("frame.tiff", std::string(tif.begin(), tif.end()))); },
                      {"frame.tiff", "PNG, JPEG or BMP"});
    }
    cv::Mat small(4, 6, CV_8UC3, cv::Scalar(1, 2, 3));
    REQUIRE(cv::imwrite(temp_path("small.png"), small));
    require_error([] { load_tactile_image(temp_path("small.png")); },
                  {"small.png", "image is 6x4 pixels; at least 8x8 needed"});
    {
        std::vector<uint8_t> png;
        REQUIRE(cv::imencode(".png", bgr_fixture(), png));
        std::string cut(png.begin(), png.begin() + long(png.size() / 2));
        require_error([&] { load_tactile_image(write_temp("cut.png", cut)); },
                      {"cut.png", "corrupt or truncated"});
    }
}
