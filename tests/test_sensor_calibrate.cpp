// vtloc calibrate's fit (engine/sensor/calibrate): a table recovered from
// presses it rendered itself, the 49 real presses half fitted and half held
// out against the shipped table, the file's round trip, and bad input.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "base/error.h"
#include "engine/sensor/ball_press.h"
#include "engine/sensor/calibrate.h"
#include "engine/sensor/gel_shading.h"
#include "tests/sim_fixtures.h"

using namespace vtloc;
using namespace vtloc::sensor;

namespace {

const Calibration& shipped() { return vtloc::test::calib(); }

double mean_inside(const Calibration& c, const std::vector<BallPress>& presses, const CalibrateOptions& o = {}) {
    double s = 0;
    for (const BallPress& p : presses) s += press_residual(c, p, o).inside;
    return s / double(presses.size());
}

// A frame as the calibration itself renders the press (no noise), rounded to 8 bits.
std::vector<uint8_t> render(const Calibration& c, const std::vector<float>& height_px) {
    std::vector<float> h = height_px, shade;
    for (size_t i = 0; i < h.size(); ++i) h[i] += c.depth_bg[i];
    GelShader(c).shade(h, shade);
    std::vector<uint8_t> f(shade.size());
    for (size_t i = 0; i < f.size(); ++i) f[i] = uint8_t(std::lround(std::clamp(double(shade[i]) + c.real_bg[i], 0.0, 255.0)));
    return f;
}

}  // namespace

TEST_CASE("calibrate: a table comes back from presses it rendered", "[sensor][calibrate]") {
    // A table smooth over its bins (like a sensor's optics; the shipped table's bins scatter
    // far more than its 49 presses pin down): a colour change of 60 x sin(slope) in a
    // direction per channel, its size varying linearly across the frame, over the
    // shipped background on a flat gel.
    Calibration c = shipped();
    std::fill(c.depth_bg.begin(), c.depth_bg.end(), 0.0f);
    const int H = c.height, W = c.width, B = c.bins;
    for (int m = 0; m < B; ++m)
        for (int d = 0; d < B; ++d)
            for (int ch = 0; ch < 3; ++ch) {
                const double slope = std::sin(m * 0.5 * M_PI / (B - 1)), dir = -M_PI + (d + 0.5) * 2 * M_PI / (B - 1);
                const double k = 60 * slope * std::cos(dir + 2.1 * ch);
                float* p = &c.poly[ch][(size_t(m) * B + size_t(d)) * 6];
                const float coef[6] = {0, 0, 0, float(k * 0.004), float(-k * 0.003), float(k * 0.8)};
                std::copy(coef, coef + 6, p);
            }
    const std::vector<uint8_t> empty = render(c, std::vector<float>(size_t(H) * W, 0.0f));
    std::vector<BallPress> fit, held;
    uint64_t state = 7;
    auto uniform = [&](double lo, double hi) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return lo + (hi - lo) * double(state >> 11) / double(1ull << 53);
    };
    for (int i = 0; i < 40; ++i) {
        BallPress p;
        p.cx = uniform(25, W - 25), p.cy = uniform(25, H - 25), p.radius_px = uniform(8, 15);
        p.frame = render(c, press_height_px(p, H, W, {}));
        (i % 4 == 3 ? held : fit).push_back(std::move(p));
    }
    CalibrateOptions o;
    o.background_sigma_px = 0;  // noise-free frames: the background needs no smoothing
    const Calibration mine = fit_calibration(fit, empty, H, W, o);
    const double ours = mean_inside(mine, held), theirs = mean_inside(c, held);
    INFO("held-out |dRGB| inside: fitted " << ours << ", the table that rendered them " << theirs);
    // The rendering table explains its frames up to 8-bit rounding (~0.25); the fit adds
    // its pooling over neighbouring bins, 1.3 from 30 presses (0.8 from 150: it converges),
    // against 7.7 on real presses; a wrong bin convention or change of polynomial basis
    // costs tens.
    CHECK(theirs < 0.5);
    CHECK(ours < 1.6);
}

TEST_CASE("calibrate: half the 49 real presses explain the other half as well as the shipped table", "[sensor][calibrate]") {
    const std::vector<BallPress> all = calibration_presses(shipped());
    REQUIRE(all.size() == 49);
    std::vector<BallPress> even, odd;
    for (size_t i = 0; i < all.size(); ++i) (i % 2 ? odd : even).push_back(all[i]);
    const Calibration mine = fit_calibration(even, shipped().press_f0, shipped().height, shipped().width);
    const double ours = mean_inside(mine, odd), theirs = mean_inside(shipped(), odd);
    std::printf("calibrate: held-out odd presses, mean |dRGB| inside: fitted on the even ones %.2f, shipped %.2f\n", ours, theirs);
    // #43's goal: within 10 % of the shipped table (measured: 7.7 against 13.2).
    CHECK(ours <= 1.10 * theirs);
    CHECK(mean_inside(mine, even) < ours + 1.0);  // and no worse on the presses it saw than off them, within a grey level
}

TEST_CASE("calibrate: the file reads back as a calibration", "[sensor][calibrate]") {
    std::vector<BallPress> some = calibration_presses(shipped());
    some.resize(6);
    const Calibration mine = fit_calibration(some, shipped().press_f0, shipped().height, shipped().width);
    const std::string path = (std::filesystem::temp_directory_path() / "vtloc_test_calibrate.safetensors").string();
    save_calibration(path, mine);
    const Calibration back = load_calibration(path);
    std::filesystem::remove(path);
    CHECK(back.bins == mine.bins);
    CHECK(back.mm_per_px == Approx(mine.mm_per_px).epsilon(1e-9));
    for (int ch = 0; ch < 3; ++ch) CHECK(back.poly[ch] == mine.poly[ch]);
    CHECK(back.real_bg == mine.real_bg);
    CHECK(back.depth_bg == mine.depth_bg);
    CHECK(back.n_press == 6);
    CHECK(back.press_imgs == mine.press_imgs);
    CHECK(back.press_radius == mine.press_radius);
    CHECK(press_residual(back, some[0]).inside == press_residual(mine, some[0]).inside);
}

TEST_CASE("calibrate: bad presses and options are refused by name", "[sensor][calibrate]") {
    const Calibration& c = shipped();
    const int H = c.height, W = c.width;
    std::vector<BallPress> ps = calibration_presses(c);
    ps.resize(3);
    CHECK_THROWS_WITH(fit_calibration({}, c.press_f0, H, W), Catch::Contains("no ball presses"));
    CHECK_THROWS_WITH(fit_calibration(ps, std::vector<uint8_t>(10), H, W), Catch::Contains("empty frame"));
    auto bad = ps;
    bad[1].frame.resize(100);
    CHECK_THROWS_WITH(fit_calibration(bad, c.press_f0, H, W), Catch::Contains("press 1: the frame is not 160x120"));
    bad = ps, bad[2].cx = W + 3;
    CHECK_THROWS_WITH(fit_calibration(bad, c.press_f0, H, W), Catch::Contains("press 2: the contact's centre"));
    bad = ps, bad[0].radius_px = 0;
    CHECK_THROWS_WITH(fit_calibration(bad, c.press_f0, H, W), Catch::Contains("press 0: the contact's radius"));
    bad = ps, bad[0].cy = std::nan("");
    CHECK_THROWS_WITH(fit_calibration(bad, c.press_f0, H, W), Catch::Contains("off the frame"));
    CalibrateOptions o;
    o.ball_radius_mm = -1;
    CHECK_THROWS_WITH(fit_calibration(ps, c.press_f0, H, W, o), Catch::Contains("options out of range"));
}

TEST_CASE("calibrate: from detected contacts, refining the circles recovers the annotation", "[sensor][calibrate]") {
    const Calibration& c = shipped();
    const std::vector<BallPress> all = calibration_presses(c);
    std::vector<BallPress> even, odd;
    for (size_t i = 0; i < all.size(); ++i) (i % 2 ? odd : even).push_back(all[i]);
    std::vector<BallPress> blind = even;
    for (BallPress& p : blind) p.radius_px = 0;  // detect
    auto median_error = [&](const std::vector<BallPress>& ps) {
        std::vector<double> d;
        for (size_t i = 0; i < ps.size(); ++i) d.push_back(std::hypot(ps[i].cx - even[i].cx, ps[i].cy - even[i].cy) + std::abs(ps[i].radius_px - even[i].radius_px));
        std::sort(d.begin(), d.end());
        return d[d.size() / 2];
    };
    const CalibrateRun detected = calibrate(blind, c.press_f0, c.height, c.width, {}, 0);
    const CalibrateRun refined = calibrate(blind, c.press_f0, c.height, c.width, {}, 2);
    const double before = median_error(detected.presses), after = median_error(refined.presses);
    const double held = mean_inside(refined.calib, odd), theirs = mean_inside(c, odd);
    std::printf("calibrate: detected circles off the annotation by %.2f px (centre + radius, median), %.2f after 2 rounds; "
                "held-out |dRGB| %.2f (detected only: %.2f; shipped %.2f)\n",
                before, after, held, mean_inside(detected.calib, odd), theirs);
    CHECK(refined.rounds == 2);
    // The colour change's halo makes detected contacts ~1.5x too wide (13.5 px off the annotation, centre + radius, median);
    // two rounds halve that, and the table explains held-out presses within #43's 10 % of the shipped one.
    CHECK(after < 0.6 * before);
    CHECK(held <= 1.10 * theirs);
}
