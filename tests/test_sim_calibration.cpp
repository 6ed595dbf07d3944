// The sensor calibration the touch renderer draws with (engine/sim/calibration.h):
// the shipped file's shapes and the loader's errors.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <iterator>

#include "base/error.h"
#include "engine/safetensors.h"
#include "engine/sensor/calibration.h"
#include "engine/sim/primitives.h"
#include "engine/sim/touch_renderer.h"
#include "tests/harness.h"
#include "tests/sim_fixtures.h"

using namespace vtloc;
using namespace vtloc::sim;

using test::calib;
using test::no_noise;

TEST_CASE("sim: the shipped calibration loads with the documented shapes", "[sim]") {
    const Calibration& c = calib();
    CHECK(c.height == 120);
    CHECK(c.width == 160);
    CHECK(c.bins == 120);
    CHECK(c.mm_per_px == Approx(0.1245));
    CHECK(c.n_press == 49);
    CHECK(c.press_imgs.size() == size_t(49) * 120 * 160 * 3);
    CHECK(c.depth_bg.size() == size_t(120) * 160);
}

TEST_CASE("sim: calibration loader errors name the file and the tensor", "[sim]") {
    const int H = 8, W = 10, B = 4;
    auto blobs = [&] {
        std::vector<TensorBlob> b;
        for (const char* n : {"poly_r", "poly_g", "poly_b"})
            b.push_back(TensorBlob::f32(n, {B, B, 6}, std::vector<float>(B * B * 6, 0.5f)));
        b.push_back(TensorBlob::f32("real_bg", {H, W, 3}, std::vector<float>(H * W * 3, 100.0f)));
        b.push_back(TensorBlob::f32("depth_bg", {H, W}, std::vector<float>(H * W, 1.0f)));
        return b;
    };
    auto expect_error = [](const std::string& path, const std::string& tensor) {
        try {
            load_calibration(path);
            FAIL("no error for " << tensor);
        } catch (const Error& e) {
            std::string m = e.what();
            INFO(m);
            CHECK(m.find(path) != std::string::npos);
            CHECK(m.find(tensor) != std::string::npos);
            CHECK(m.find('\n') == std::string::npos);
        }
    };
    const std::string good = test::temp_path("sim_calib_good.safetensors");
    write_safetensors(good, blobs(), {});
    Calibration c = load_calibration(good);
    CHECK(c.height == H);
    CHECK(c.width == W);
    CHECK(c.bins == B);
    CHECK(c.n_press == 0);
    // A tiny sensor renders too (no press frames needed).
    Touch t = TouchRenderer(c, make_plane(50, 50), 0.5).render({0, 0, 0}, {0, 0, 1}, TouchParams{}, no_noise(), 0);
    CHECK(t.ok);
    CHECK(t.image.size() == size_t(H) * W * 3);

    auto missing = blobs();
    missing.erase(missing.begin() + 1);
    const std::string p1 = test::temp_path("sim_calib_missing.safetensors");
    write_safetensors(p1, missing, {});
    expect_error(p1, "poly_g");

    auto shape = blobs();
    shape[4] = TensorBlob::f32("depth_bg", {H, W + 1}, std::vector<float>(H * (W + 1), 1.0f));
    const std::string p2 = test::temp_path("sim_calib_shape.safetensors");
    write_safetensors(p2, shape, {});
    expect_error(p2, "depth_bg");

    auto nonfinite = blobs();
    std::vector<float> bg(H * W * 3, 100.0f);
    bg[17] = std::nanf("");
    nonfinite[3] = TensorBlob::f32("real_bg", {H, W, 3}, bg);
    const std::string p3 = test::temp_path("sim_calib_nan.safetensors");
    write_safetensors(p3, nonfinite, {});
    expect_error(p3, "real_bg");

    auto dtype = blobs();
    dtype[0] = TensorBlob::i32("poly_r", {B, B, 6}, std::vector<int32_t>(B * B * 6, 1));
    const std::string p4 = test::temp_path("sim_calib_dtype.safetensors");
    write_safetensors(p4, dtype, {});
    expect_error(p4, "poly_r");

    auto press = blobs();
    press.push_back(TensorBlob::f32("press_center", {2, 2}, std::vector<float>(4, 1.0f)));
    TensorBlob imgs;
    imgs.name = "press_imgs";
    imgs.dtype = DType::U8;
    imgs.shape = {2, H, W, 3};
    imgs.bytes.assign(2 * H * W * 3, 0);
    press.push_back(imgs);
    const std::string p5 = test::temp_path("sim_calib_press.safetensors");
    write_safetensors(p5, press, {});
    expect_error(p5, "press_f0");  // press frames without their empty frame

    const std::string nofile = test::temp_path("sim_calib_does_not_exist.safetensors");
    try {
        load_calibration(nofile);
        FAIL("no error");
    } catch (const Error& e) {
        CHECK(std::string(e.what()).find(nofile) != std::string::npos);
        CHECK(std::string(e.what()).find("not a calibration") == std::string::npos);  // it is no file at all
    }
    // A file that is not tensors at all (a JSON given as the calibration) says what it likely is.
    const std::string json = test::temp_path("sim_calib_not.json");
    std::ofstream(json) << "{\"x\": 1}\n";
    CHECK_THROWS_WITH(load_calibration(json), Catch::Contains(json) && Catch::Contains("(not a calibration file?)"));
}

TEST_CASE("sim: a calibration parsed from bytes equals the file's, and bad bytes name their source", "[sim]") {
    const std::string path = sensor::default_calibration_path();
    std::ifstream f(path, std::ios::binary);
    std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(f)), {});
    REQUIRE(bytes.size() > 1000);
    const Calibration a = sensor::parse_calibration(bytes, "memory"), &b = calib();
    CHECK(a.poly[1] == b.poly[1]);
    CHECK(a.real_bg == b.real_bg);
    CHECK(a.press_radius == b.press_radius);
    CHECK(a.mm_per_px == b.mm_per_px);
    bytes.resize(bytes.size() / 2);  // data cut off
    CHECK_THROWS_WITH(sensor::parse_calibration(bytes, "half.safetensors"), Catch::StartsWith("half.safetensors"));
}
