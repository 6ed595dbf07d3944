// The gel's shape from a frame, CPU reference (engine/sensor/gel_shape): on the
// calibration's own rendering of a ball press, and on the 49 real ball presses
// of data/gelsight (a 4 mm ball): the fitted sphere's radius, the cap's depth
// and the mask's centre against the annotation. docs/gel_shape.md has the numbers.
#include <catch2/catch.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "engine/sensor/calibration.h"
#include "engine/sensor/gel_shading.h"
#include "engine/sensor/gel_shape.h"
#include "engine/sensor/lighting.h"
#include "tests/sim_fixtures.h"

using namespace vtloc;
using namespace vtloc::sensor;

namespace {

using vtloc::test::calib;
const GradientLut& lut() {
    static const GradientLut l = build_gradient_lut(calib());
    return l;
}

// The sphere through the contact (mask eroded by 2 px, as the cap's rim is least sure), in mm.
Sphere cap_sphere(const GelShape& s, double px) {
    std::vector<double> xyz;
    for (int r = 2; r < s.height - 2; ++r)
        for (int c = 2; c < s.width - 2; ++c) {
            bool inside = true;
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx)
                    if (dx * dx + dy * dy <= 4) inside = inside && s.mask[size_t(r + dy) * s.width + size_t(c + dx)];
            if (inside) xyz.insert(xyz.end(), {c * px, r * px, double(s.depth_mm[size_t(r) * s.width + size_t(c)])});
        }
    return fit_sphere(xyz);
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

}  // namespace

TEST_CASE("gel shape: the sphere fit recovers a known sphere", "[sensor]") {
    std::vector<double> xyz;
    for (int i = 0; i < 200; ++i) {
        const double th = 0.1 + 0.004 * i, ph = 0.37 * i;
        xyz.insert(xyz.end(), {1 + 2 * std::sin(th) * std::cos(ph), -3 + 2 * std::sin(th) * std::sin(ph), 5 - 2 * std::cos(th)});
    }
    const Sphere s = fit_sphere(xyz);
    CHECK(s.radius == Approx(2).margin(1e-9));
    CHECK(s.centre[2] == Approx(5).margin(1e-9));
    CHECK_THROWS(fit_sphere({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0}));  // coplanar
}

TEST_CASE("gel shape: the tables are the same bits on any number of host threads", "[sensor]") {
    // A coarser grid than the reader's (n 32, every 8th pixel): the same code, a quarter of the work.
    const LutGrid grid{32, 3, 4, 8};
    const GradientLut one = build_gradient_lut(calib(), 1, grid), three = build_gradient_lut(calib(), 3, grid);
    REQUIRE(one.table.size() == size_t(12) * 32 * 32 * 32 * 2);
    CHECK(one.table == three.table);
    CHECK(one.linear == three.linear);
    CHECK(std::any_of(one.table.begin(), one.table.end(), [](float v) { return v != 0; }));
    CHECK_THROWS_WITH(build_gradient_lut(calib(), -1, grid), Catch::Contains("threads must be >= 0"));
}

TEST_CASE("gel shape: a ball press rendered with the calibration comes back", "[sensor]") {
    const Calibration& c = calib();
    const int H = c.height, W = c.width;
    const double px = c.mm_per_px, R = 2.0 / px, a = 12, cx = 83.5, cy = 57.25;  // pixels
    const double d = R - std::sqrt(R * R - a * a);
    std::vector<float> h(c.depth_bg), ind(size_t(H) * W, 0.f);
    for (int r = 0; r < H; ++r)
        for (int col = 0; col < W; ++col) {
            const double q = (col - cx) * (col - cx) + (r - cy) * (r - cy);
            if (q < a * a) ind[size_t(r) * W + size_t(col)] = float(std::sqrt(R * R - q) - (R - d));
        }
    // Undraped: the contact's edge is sharp. With the renderer's drape the steep ring spreads out
    // and the gradient threshold's mask misses most of the contact (IoU 0.3): docs/gel_shape.md.
    for (size_t i = 0; i < h.size(); ++i) h[i] += ind[i];
    GelShader shader(c);
    auto render = [&](const std::vector<float>& height) {
        std::vector<float> s;
        shader.shade(height, s);
        std::vector<uint8_t> f(s.size());
        for (size_t i = 0; i < s.size(); ++i) f[i] = uint8_t(std::clamp(std::floor(s[i] + c.real_bg[i] + 0.5f), 0.f, 255.f));
        return f;
    };
    // A shallow press (0.67 mm, contact 12 px): its steep ring is thin, so the mask threshold
    // fitted on the real presses (0.7, deep presses) keeps only part of it; 0.5 finds the contact.
    ShapeOptions o;
    o.mask_threshold = 0.5;
    const GelShape s = gel_shape(c, lut(), render(h), render(c.depth_bg), o);
    size_t both = 0, either = 0;
    double se = 0, deepest = 0;
    int n = 0;
    for (size_t i = 0; i < ind.size(); ++i) {
        both += ind[i] > 0 && s.mask[i], either += ind[i] > 0 || s.mask[i];
        deepest = std::max(deepest, double(s.depth_mm[i]));
        if (ind[i] > 0) se += std::pow(s.depth_mm[i] - ind[i] * px, 2), ++n;
    }
    const double rms = std::sqrt(se / n), depth_mm = d * px, iou = double(both) / double(either);
    INFO("synthetic press: depth " << depth_mm << " mm, reconstructed " << deepest
                                    << " mm, RMS inside the contact " << rms << " mm, mask IoU " << iou);
    CHECK(iou > 0.85);  // measured 0.94
    // The cap comes out too deep (1.5x): the tables overestimate steep slopes (the colours saturate
    // above ~50 degrees). #43's goal, RMS <= 20 % of the press depth, is not met: 29 % here.
    CHECK(deepest > 1.0 * depth_mm);
    CHECK(deepest < 2.0 * depth_mm);
    CHECK(rms < 0.4 * depth_mm);
}

TEST_CASE("gel shape: the 49 real ball presses give the 2 mm ball", "[sensor]") {
    const Calibration& c = calib();
    REQUIRE(c.n_press == 49);
    const size_t frame = size_t(c.height) * c.width * 3;
    // As read (the CPU reference) and with the lighting matched first (what api::GelShapeReader does).
    for (bool match : {false, true}) {
        std::vector<double> radius, offset;
        ShapeOptions o;  // the defaults: the mask threshold 0.7 was fitted on these presses (numpy prototype)
        for (int i = 0; i < c.n_press; ++i) {
            std::vector<uint8_t> f(c.press_imgs.begin() + long(i * frame), c.press_imgs.begin() + long((i + 1) * frame));
            if (match) f = match_lighting(f, c.press_f0);
            const GelShape s = gel_shape(c, lut(), f, c.press_f0, o);
            radius.push_back(cap_sphere(s, c.mm_per_px).radius);
            double sx = 0, sy = 0, m = 0;
            for (int r = 0; r < c.height; ++r)
                for (int col = 0; col < c.width; ++col)
                    if (s.mask[size_t(r) * c.width + size_t(col)]) sx += col, sy += r, ++m;
            REQUIRE(m > 0);
            offset.push_back(std::hypot(sx / m - c.press_center[size_t(2 * i)], sy / m - c.press_center[size_t(2 * i + 1)]));
        }
        const double med_r = median(radius), med_off = median(offset);
        INFO("lighting matched: " << match << "; real presses: median fitted radius " << med_r << " mm, mask centre offset " << med_off << " px");
        CHECK(std::abs(med_r - 2.0) <= 0.2 * 2.0);  // SPEC 9 / #43's goal on the median frame
        // The annotation itself is off by a few pixels (frames 6 and 24 share one while 1.4-1.7 px apart).
        CHECK(med_off < 4);
    }
}
