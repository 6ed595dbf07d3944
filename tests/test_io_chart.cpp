// The line chart vtloc eval --sequence --plot draws: a PNG of the requested size
// with the series drawn in colour, and clear errors for what cannot be drawn.
#include <catch2/catch.hpp>
#include <cmath>
#include <map>

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

namespace {

io::LineChart flat_lines(size_t n, const std::string& name) {
    io::LineChart c;
    c.x = {1, 2, 3};
    for (size_t k = 0; k < n; ++k) c.series.push_back({name + std::to_string(k), {double(k + 1), double(k + 1), double(k + 1)}, false});
    return c;
}

}  // namespace

TEST_CASE("line chart: ten series get ten colours", "[io][chart]") {
    // The palette once had eight colours: the ninth series took the first's. One of the ten is
    // grey, which the saturation test below does not see: nine saturated colours.
    const std::string path = test::temp_path("chart10.png");
    io::save_line_chart_png(path, flat_lines(10, "method "));
    const io::RgbImage img = io::load_tactile_image(path);
    std::map<int, int> count;  // exact saturated colours (anti-aliased edges blend, line cores do not)
    for (size_t i = 0; i + 2 < img.pixels.size(); i += 3) {
        const int r = img.pixels[i], g = img.pixels[i + 1], b = img.pixels[i + 2];
        if (std::max({std::abs(r - g), std::abs(g - b), std::abs(r - b)}) > 60) ++count[(r << 16) | (g << 8) | b];
    }
    int colours = 0;
    for (const auto& [rgb, n] : count) colours += n >= 40;
    CHECK(colours >= 9);
}

TEST_CASE("line chart: a long label is cut with an ellipsis inside the image, not at its edge", "[io][chart]") {
    io::LineChart c = flat_lines(2, std::string(120, 'W'));
    c.width = 900, c.height = 400;
    const std::string path = test::temp_path("chart_long.png");
    io::save_line_chart_png(path, c);
    const io::RgbImage img = io::load_tactile_image(path);
    int inked = 0;  // the last 4 columns stay white
    for (int y = 0; y < img.height; ++y)
        for (int x = img.width - 4; x < img.width; ++x) {
            const size_t i = (size_t(y) * img.width + x) * 3;
            inked += img.pixels[i] < 250 || img.pixels[i + 1] < 250 || img.pixels[i + 2] < 250;
        }
    CHECK(inked == 0);
}
