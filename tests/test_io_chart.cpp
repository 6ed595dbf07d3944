// The line chart vtloc eval --sequence --plot draws: a PNG of the requested size
// with the series drawn in colour, and clear errors for what cannot be drawn.
#include <catch2/catch.hpp>
#include <cmath>

#include "engine/io/image.h"
#include "engine/io/line_chart.h"
#include "tests/io_test_util.h"

using namespace vtloc;

TEST_CASE("line chart: a PNG of the chart's size with its series in colour", "[io][chart]") {
    io::LineChart c;
    c.title = "ND against T";
    c.x = {1, 2, 4, 8};
    c.series = {{"geometry", {40, 30, NAN, 2}, false}, {"up to symmetry", {35, 20, 10, 1}, true}};
    c.width = 700, c.height = 420;
    const std::string path = test::temp_path("chart.png");
    io::save_line_chart_png(path, c);
    const io::RgbImage img = io::load_tactile_image(path);
    CHECK((img.width == 700 && img.height == 420));
    size_t coloured = 0;  // the lines: pixels far from grey
    for (size_t i = 0; i + 2 < img.pixels.size(); i += 3) {
        const int r = img.pixels[i], g = img.pixels[i + 1], b = img.pixels[i + 2];
        coloured += std::max({std::abs(r - g), std::abs(g - b), std::abs(r - b)}) > 60;
    }
    CHECK(coloured > 500);
}

TEST_CASE("line chart: nothing to draw or mismatched series are errors naming the file", "[io][chart][errors]") {
    io::LineChart c;
    test::require_error([&] { io::save_line_chart_png("/tmp/a.png", c); }, {"/tmp/a.png", "needs x values"});
    c.x = {1, 2};
    c.series = {{"short", {1}, false}};
    test::require_error([&] { io::save_line_chart_png("/tmp/a.png", c); }, {"/tmp/a.png", "'short' has 1 values for 2 x"});
    c.series = {{"ok", {1, 2}, false}};
    test::require_error([&] { io::save_line_chart_png("/no/such/dir/a.png", c); }, {"/no/such/dir/a.png"});
}
