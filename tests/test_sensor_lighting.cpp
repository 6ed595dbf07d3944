// engine/sensor/lighting.h: a frame's gain and offset per channel against the empty
// frame, fitted on the pixels the gel leaves flat, and undone.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <random>

#include "base/error.h"
#include "engine/sensor/lighting.h"

using namespace vtloc;

namespace {

// An empty frame with the LEDs' spatial falloff (each channel its own slope), H x W x 3.
std::vector<uint8_t> empty_frame(int H, int W) {
    std::vector<uint8_t> e(size_t(H * W * 3));
    for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c)
            for (int k = 0; k < 3; ++k) e[size_t((r * W + c) * 3 + k)] = uint8_t(40 + 20 * k + c + r);
    return e;
}

}  // namespace

TEST_CASE("lighting: a gain and offset per channel come back around a press, and are undone", "[sensor]") {
    const int H = 48, W = 64;
    const std::vector<uint8_t> e = empty_frame(H, W);
    const double gain[3] = {0.8, 1.15, 1.2}, offset[3] = {12, -20, 5};
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0, 1.5);
    std::vector<uint8_t> f(e.size()), shaded(e.size());
    for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c)
            for (int k = 0; k < 3; ++k) {
                const size_t i = size_t((r * W + c) * 3 + k);
                // A press covering a fifth of the frame shades it strongly.
                const double shade = std::hypot(r - 20, c - 30) < 12 ? (k == 1 ? 40.0 : -30.0) : 0.0;
                shaded[i] = uint8_t(std::clamp(e[i] + shade, 0.0, 255.0));
                f[i] = uint8_t(std::clamp(std::lround(gain[k] * (e[i] + shade) + offset[k] + noise(rng)), 0L, 255L));
            }
    sensor::LightingFit fit;
    const std::vector<uint8_t> m = sensor::match_lighting(f, e, &fit);
    for (int k = 0; k < 3; ++k) {
        INFO("channel " << k);
        CHECK(fit.gain[k] == Approx(gain[k]).margin(0.02));
        CHECK(fit.offset[k] == Approx(offset[k]).margin(2.5));  // noise 1.5 levels, rounding
    }
    double worst = 0, mean = 0;
    for (size_t i = 0; i < m.size(); ++i) {
        worst = std::max(worst, std::abs(double(m[i]) - double(shaded[i])));
        mean += std::abs(double(m[i]) - double(shaded[i])) / double(m.size());
    }
    CHECK(mean <= 1.5);   // the noise (sigma 1.5: mean |n| 1.2) over the gain, and rounding
    CHECK(worst <= 9.0);  // its tail: 4.5 sigma / gain 0.8 + rounding
}

TEST_CASE("lighting: the empty frame itself is left as it is, and bad sizes and flat channels", "[sensor]") {
    const std::vector<uint8_t> e = empty_frame(30, 40);
    sensor::LightingFit fit;
    CHECK(sensor::match_lighting(e, e, &fit) == e);
    for (int k = 0; k < 3; ++k) CHECK((fit.gain[k] == Approx(1.0) && fit.offset[k] == Approx(0.0).margin(1e-9)));
    // A channel without spatial variation cannot separate gain from offset: the offset alone.
    std::vector<uint8_t> flat(e.size(), 100), brighter(e.size(), 110);
    const sensor::LightingFit f2 = sensor::fit_lighting(brighter, flat);
    CHECK((f2.gain[0] == 1.0 && f2.offset[0] == Approx(10.0)));
    CHECK_THROWS_WITH(sensor::fit_lighting(e, std::vector<uint8_t>(e.begin(), e.end() - 3)),
                      Catch::Contains("lighting: the frame and the empty frame differ in size"));
}
