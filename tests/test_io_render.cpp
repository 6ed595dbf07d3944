// Heat-map colour map and PNG render.
#include <catch2/catch.hpp>
#include <cmath>

#include "engine/io/colormap.h"
#include "engine/io/image.h"
#include "engine/io/object.h"
#include "engine/io/render.h"
#include "tests/io_test_util.h"

using namespace vtloc;
using namespace vtloc::io;

namespace {

double luminance(std::array<uint8_t, 3> c) {
    auto lin = [](double v) {
        v /= 255;
        return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
    };
    return 0.2126 * lin(c[0]) + 0.7152 * lin(c[1]) + 0.0722 * lin(c[2]);
}

// SPEC section 3's heat-map for a single best candidate c: min-max normalised
// exp(-||p - c||) in the normalised frame.
std::vector<float> heat_around(const HostTensor& cloud, const std::array<float, 3>& c) {
    const int64_t n = cloud.shape[0];
    double centre[3] = {0, 0, 0}, scale = 0;
    for (int64_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) centre[k] += cloud.data[size_t(i) * 6 + size_t(k)] / double(n);
    auto dist = [&](const float* p, const double* q) {
        return std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
    };
    for (int64_t i = 0; i < n; ++i) scale = std::max(scale, dist(&cloud.data[size_t(i) * 6], centre));
    double cc[3] = {c[0], c[1], c[2]};
    std::vector<float> h(static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i) h[size_t(i)] = float(std::exp(-dist(&cloud.data[size_t(i) * 6], cc) / scale));
    auto [lo, hi] = std::minmax_element(h.begin(), h.end());
    float l = *lo, r = *hi - *lo;
    for (float& v : h) v = r > 0 ? (v - l) / r : 0.0f;
    return h;
}

}  // namespace

TEST_CASE("heat colour map: ends, clamping and rising lightness", "[io]") {
    CHECK(heat_color(0.0f) == std::array<uint8_t, 3>{12, 22, 72});
    CHECK(heat_color(1.0f) == std::array<uint8_t, 3>{252, 236, 120});
    CHECK(heat_color(-3.0f) == heat_color(0.0f));
    CHECK(heat_color(7.0f) == heat_color(1.0f));
    CHECK(heat_color(NAN) == heat_color(0.0f));
    for (int i = 1; i <= 255; ++i)
        REQUIRE(luminance(heat_color(float(i) / 255)) > luminance(heat_color(float(i - 1) / 255)));
}

TEST_CASE("render of the example mug with prediction, truth and tactile inset", "[io]") {
    const std::string dir = std::string(VTLOC_SOURCE_DIR) + "/examples/";
    // The model's cloud carries the heat; a denser sample of the mesh shows it.
    HostTensor model_cloud = load_object(dir + "mug.glb", 1024);
    HostTensor cloud = load_object(dir + "mug.glb", 8192, 1);
    RgbImage touch = load_tactile_image(dir + "touch_02.png");
    RenderOptions o;
    o.ground_truth = std::array<float, 3>{54.2327f, 50.0f, 0.0f};
    o.contact = std::array<float, 3>{52.0f, 58.0f, 4.0f};
    o.caption = "mug.glb + touch_02.png: predicted (52.0, 58.0, 4.0) mm, true (54.2, 50.0, 0.0) mm, error 9.2 mm";
    o.tactile = &touch;
    std::vector<float> heat = nearest_heat(model_cloud, heat_around(model_cloud, *o.contact), cloud);
    REQUIRE(heat.size() == 8192);
    RgbImage img = render_heatmap(cloud, heat, o);
    CHECK(img.width == 1280);
    CHECK(img.height == 720);
    CHECK(render_heatmap(cloud, heat, o).pixels == img.pixels);  // deterministic
    // Both ends of the colour map appear (shaded), and the white marker ring.
    bool white = false, hot = false;
    for (size_t i = 0; i < img.pixels.size(); i += 3) {
        const uint8_t* p = &img.pixels[i];
        white = white || (p[0] == 255 && p[1] == 255 && p[2] == 255);
        hot = hot || (p[0] > 200 && p[1] > 180 && p[2] < 140);
    }
    CHECK(white);
    CHECK(hot);
    save_png(vtloc::test::temp_path("render_mug.png"), img);

    // The model's own 1024 points, as they are.
    save_png(vtloc::test::temp_path("render_model_cloud.png"),
             render_heatmap(model_cloud, heat_around(model_cloud, *o.contact), o));

    RenderOptions plain;  // no markers, no inset: the 3/4 view
    save_png(vtloc::test::temp_path("render_plain.png"), render_heatmap(cloud, heat, plain));
    vtloc::test::require_error([&] { render_heatmap(cloud, std::vector<float>(3), plain); }, {"3 heat values for 8192 points"});
    // Degenerate clouds still give a picture.
    HostTensor one({1, 6}, std::vector<float>{1, 2, 3, 0, 0, 1});
    CHECK(render_heatmap(one, std::vector<float>{1.0f}, plain).width == 1280);
}
