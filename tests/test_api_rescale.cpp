// The sensor rescale before the crop (LocalizeOptions::mm_per_px,
// rescale_tactile_image): the same millimetres at another resolution give the
// same network input, the PyTorch reference's rescale byte for byte, and the
// errors for models without a sensor and for bad pixel sizes.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "engine/safetensors.h"
#include "tests/api_test_util.h"

using namespace vtloc;

namespace {

constexpr double kModelMm = 0.1245;  // vtloc-tiny-sensor's sensor.mm_per_px

std::string sensor_model() { return test::source_path("weights_tools/goldens/vtloc-tiny-sensor.safetensors"); }

api::TactileImage example_image() { return api::load_tactile_image(test::source_path("examples/touch_01.png")); }

// Each pixel as a 2 x 2 block: the frame at twice the resolution.
api::TactileImage replicate2(const api::TactileImage& im) {
    api::TactileImage out{im.height * 2, im.width * 2, std::vector<uint8_t>(im.rgb.size() * 4)};
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x)
            for (int c = 0; c < 3; ++c)
                out.rgb[(size_t(y) * size_t(out.width) + size_t(x)) * 3 + size_t(c)] =
                    im.rgb[(size_t(y / 2) * size_t(im.width) + size_t(x / 2)) * 3 + size_t(c)];
    return out;
}

// A smooth scene (grey levels of a product of sines, mm coordinates about the
// frame centre) sampled at pixel centres of `mm` pixels, rounded to uint8.
api::TactileImage scene(int h, int w, double mm) {
    api::TactileImage im{h, w, std::vector<uint8_t>(size_t(h) * size_t(w) * 3)};
    auto level = [&](int y, int x) {
        const double v = (y - (h - 1) / 2.0) * mm, u = (x - (w - 1) / 2.0) * mm;
        return 128 + 90 * std::sin(u / 2.0) * std::cos(v / 1.5);
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double b = level(y, x), flipped = level(y, w - 1 - x);
            const double rgb[3] = {b, flipped, 255 - b};
            for (int c = 0; c < 3; ++c)
                im.rgb[(size_t(y) * size_t(w) + size_t(x)) * 3 + size_t(c)] =
                    uint8_t(std::clamp(std::floor(rgb[c] + 0.5), 0.0, 255.0));
        }
    return im;
}

const api::Tensor& tensor(const api::TouchResult& r, const std::string& name) {
    for (const api::Tensor& t : r.tensors)
        if (t.name == name) return t;
    FAIL("no tensor " << name);
    throw 0;
}

bool has_tensor(const api::TouchResult& r, const std::string& name) {
    for (const api::Tensor& t : r.tensors)
        if (t.name == name) return true;
    return false;
}

double max_diff(const std::vector<float>& a, const std::vector<float>& b) {
    REQUIRE(a.size() == b.size());
    double m = 0;
    for (size_t i = 0; i < a.size(); ++i) m = std::max(m, double(std::abs(a[i] - b[i])));
    return m;
}

api::Object mug(api::Model& model, api::Backend b) {
    return model.encode_object(test::source_path("examples/mug.glb"), test::source_path("examples/mug_candidates.csv"), b);
}

}  // namespace

TEST_CASE("api: a model's sensor is read from its config", "[api][rescale]") {
    api::ModelInfo info = api::inspect_model(sensor_model());
    REQUIRE(info.sensor.has_value());
    CHECK(info.sensor->mm_per_px == kModelMm);
    CHECK(info.sensor->height == 120);
    CHECK(info.sensor->width == 160);
    CHECK_FALSE(api::inspect_model(test::tiny_model()).sensor.has_value());
}

TEST_CASE("api: rescale_tactile_image sizes and exact cases", "[api][rescale]") {
    const api::TactileImage im = example_image();
    REQUIRE(im.height == 120);
    REQUIRE(im.width == 160);
    // round(n * s), halves up: 120 * 2/3 = 80, 160 * 2/3 = 106.67 -> 107; 120 * 4/3 = 160, 160 * 4/3 = 213.3 -> 213
    api::TactileImage fine = api::rescale_tactile_image(im, 0.083, kModelMm);
    CHECK(fine.height == 80);
    CHECK(fine.width == 107);
    api::TactileImage coarse = api::rescale_tactile_image(im, 0.166, kModelMm);
    CHECK(coarse.height == 160);
    CHECK(coarse.width == 213);
    CHECK(api::rescale_tactile_image(im, kModelMm, kModelMm).rgb == im.rgb);  // equal sizes: unchanged
    // 2 x 2 blocks at half the pixel size: the area average of a block is its pixel.
    api::TactileImage back = api::rescale_tactile_image(replicate2(im), kModelMm / 2, kModelMm);
    CHECK(back.height == im.height);
    CHECK(back.width == im.width);
    CHECK(back.rgb == im.rgb);
    // A constant frame stays constant both ways (weights sum to 1 up to rounding).
    api::TactileImage flat{50, 70, std::vector<uint8_t>(50 * 70 * 3, 77)};
    for (double mm : {0.05, 0.07, 0.2, 0.31}) {
        api::TactileImage r = api::rescale_tactile_image(flat, mm, kModelMm);
        CHECK(std::all_of(r.rgb.begin(), r.rgb.end(), [](uint8_t v) { return v == 77; }));
    }
}

TEST_CASE("api: the same touch at twice the pixel count and half the pixel size gives the same input",
          "[api][rescale]") {
    api::Context ctx(test::validated());
    api::Model model(ctx, sensor_model());
    api::Object obj = mug(model, api::Backend::Gpu);
    api::LocalizeOptions plain;
    plain.keep_tensors = true;
    api::LocalizeOptions half = plain;
    half.mm_per_px = kModelMm / 2;

    SECTION("pixel blocks: bit for bit") {
        const api::TactileImage im = example_image();
        api::TouchResult want = model.localize(obj, im, plain);
        api::TouchResult got = model.localize(obj, replicate2(im), half);
        CHECK_FALSE(has_tensor(want, "tactile.rescaled"));
        CHECK(tensor(got, "tactile.rescaled").u8 == im.rgb);
        CHECK(tensor(got, "input.tactile").shape == std::vector<int64_t>{240, 320, 3});  // the frame as given
        CHECK(tensor(got, "tactile.input").f32 == tensor(want, "tactile.input").f32);
        CHECK(got.contact == want.contact);
    }
    SECTION("one smooth scene sampled at both pixel sizes") {
        // Each frame is rounded to grey levels once; the rescaled one again after
        // averaging, so the two differ by at most one level (the scene's curvature
        // over a quarter pixel adds < 0.01 level). Crop and bilinear resize to
        // in_size are convex combinations, so tactile.input differs by at most
        // 1.01 / 255 / std (smallest ImageNet std 0.224).
        api::TouchResult want = model.localize(obj, scene(120, 160, kModelMm), plain);
        api::TouchResult got = model.localize(obj, scene(240, 320, kModelMm / 2), half);
        const double d = max_diff(tensor(got, "tactile.input").f32, tensor(want, "tactile.input").f32);
        INFO("max |difference| " << d);
        CHECK(d <= 1.01 / 255 / 0.224);
        CHECK(d > 0);  // really two different frames
    }
    SECTION("batches rescale every frame") {
        const api::TactileImage im = example_image();
        api::TouchResult want = model.localize(obj, im, plain);
        std::vector<api::TactileImage> frames{replicate2(im), replicate2(im)};
        for (const api::TouchResult& r : model.localize(obj, frames, half))
            CHECK(tensor(r, "tactile.input").f32 == tensor(want, "tactile.input").f32);
    }
    test::require_no_validation(ctx);
}

TEST_CASE("api: the rescaled input equals the PyTorch reference's", "[api][rescale]") {
    api::Context ctx(test::validated());
    api::Model model(ctx, sensor_model());
    for (const char* label : {"coarse", "fine"}) {
        INFO(label);
        const std::string path =
            test::source_path(std::string("weights_tools/goldens/vtloc-tiny-sensor.") + label + ".golden.safetensors");
        SafetensorsFile g = SafetensorsFile::load(path);
        const double mm = std::stod(g.metadata().at("vtloc.golden.mm_per_px"));
        const TensorInfo& t = g.at("input.tactile");
        auto bytes = g.bytes(t);
        api::TactileImage image{int(t.shape[0]), int(t.shape[1]), std::vector<uint8_t>(bytes.begin(), bytes.end())};
        std::vector<float> raw = g.to_f32(g.at("input.cloud"));
        api::PointCloud cloud;
        for (size_t i = 0; i < raw.size(); i += 6) {
            cloud.xyz.insert(cloud.xyz.end(), raw.begin() + long(i), raw.begin() + long(i) + 3);
            cloud.normals.insert(cloud.normals.end(), raw.begin() + long(i) + 3, raw.begin() + long(i) + 6);
        }
        api::Object obj = model.encode_object(cloud, g.to_f32(g.at("input.candidates")));
        api::LocalizeOptions opt;
        opt.keep_tensors = true;
        opt.mm_per_px = mm;
        for (api::Backend b : {api::Backend::Gpu, api::Backend::Cpu}) {
            opt.backend = b;
            api::Object o = b == api::Backend::Gpu ? obj : model.encode_object(cloud, g.to_f32(g.at("input.candidates")), b);
            api::TouchResult r = model.localize(o, image, opt);
            const TensorInfo& rs = g.at("tactile.rescaled");
            auto want_rs = g.bytes(rs);
            CHECK(tensor(r, "tactile.rescaled").shape == rs.shape);
            CHECK(tensor(r, "tactile.rescaled").u8 == std::vector<uint8_t>(want_rs.begin(), want_rs.end()));
            const double d = max_diff(tensor(r, "tactile.input").f32, g.to_f32(g.at("tactile.input")));
            INFO("tactile.input max |difference| " << d);
            CHECK(d <= 1e-5);
        }
    }
    test::require_no_validation(ctx);
}

TEST_CASE("api: mm_per_px errors", "[api][rescale]") {
    api::Model tiny(test::tiny_model());
    api::Object obj = mug(tiny, api::Backend::Cpu);
    api::LocalizeOptions opt;
    opt.backend = api::Backend::Cpu;
    opt.mm_per_px = 0.1;
    const api::TactileImage im = example_image();
    for (auto call : std::initializer_list<std::function<void()>>{
             [&] { tiny.localize(obj, im, opt); }, [&] { tiny.localize(obj, std::vector<api::TactileImage>{im, im}, opt); }}) {
        std::string m = test::api_error(call);
        CHECK(m == test::tiny_model() + " has no sensor pixel size in its config; cannot rescale");
    }

    api::Model model(sensor_model());
    api::Object sobj = mug(model, api::Backend::Cpu);
    for (double bad : {0.0, -0.1, std::nan(""), std::numeric_limits<double>::infinity()}) {
        opt.mm_per_px = bad;
        std::string m = test::api_error([&] { model.localize(sobj, im, opt); });
        CHECK(m.rfind("mm_per_px must be a finite number > 0, got ", 0) == 0);
        m = test::api_error([&] { api::rescale_tactile_image(im, bad, kModelMm); });
        CHECK(m.rfind("mm_per_px must be a finite number > 0", 0) == 0);
    }
    opt.mm_per_px = 0.001;  // 120 x 160 of 1 um pixels: 1 x 1 at 0.1245 mm
    CHECK_THAT(test::api_error([&] { model.localize(sobj, im, opt); }),
               Catch::Contains("gives 1x1; the smallest accepted is 8x8"));
    opt.mm_per_px = 100.0;
    CHECK_THAT(test::api_error([&] { model.localize(sobj, im, opt); }), Catch::Contains("pixels a side"));
}
