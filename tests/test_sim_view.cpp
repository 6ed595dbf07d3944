// vtloc synth --view: the single-view cloud of an object as a depth camera far
// away sees it (engine/sim/partial_view.h).
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "engine/sim/partial_view.h"
#include "engine/sim/primitives.h"
#include "tests/harness.h"

using namespace vtloc;

TEST_CASE("a partial view of a sphere is the hemisphere facing the camera", "[sim]") {
    const io::TriangleMesh ball = sim::make_icosphere(30, 4, {5, -2, 7});
    const sim::PartialView v = sim::render_partial_view(ball, 42, 500);
    REQUIRE(v.xyz.shape == Shape{500, 3});
    CHECK(v.visible_pixels > 500);
    size_t front = 0;
    for (int64_t i = 0; i < 500; ++i) {
        const double p[3] = {v.xyz.data[size_t(i * 3)] - 5.0, v.xyz.data[size_t(i * 3 + 1)] + 2.0,
                             v.xyz.data[size_t(i * 3 + 2)] - 7.0};
        const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        CHECK(std::abs(r - 30) < 0.2);  // on the tessellated sphere (chord error of level 4)
        const double facing = (p[0] * v.direction[0] + p[1] * v.direction[1] + p[2] * v.direction[2]) / r;
        front += facing < 0.05;  // the camera looks along +direction: it sees the -direction side (rim: grazing)
    }
    CHECK(front == 500);
    // the camera point lies on the seen side, far away
    const double cam[3] = {v.camera[0] - 5, v.camera[1] + 2, v.camera[2] - 7};
    CHECK(cam[0] * v.direction[0] + cam[1] * v.direction[1] + cam[2] * v.direction[2] < -500);
}

TEST_CASE("partial views are seeded: the same seed gives the same view, another seed another", "[sim]") {
    const io::TriangleMesh ball = sim::make_icosphere(30, 3);
    const sim::PartialView a = sim::render_partial_view(ball, 7, 100), b = sim::render_partial_view(ball, 7, 100),
                           c = sim::render_partial_view(ball, 8, 100);
    CHECK(a.xyz.data == b.xyz.data);
    CHECK(a.direction == b.direction);
    CHECK(a.direction != c.direction);
    // fewer visible pixels than asked: all of them
    const sim::PartialView few = sim::render_partial_view(ball, 7, 100000, 16);
    CHECK(few.xyz.shape[0] == few.visible_pixels);
}

TEST_CASE("write_partial_view writes view.xyz and view.json", "[sim]") {
    const std::filesystem::path dir = test::temp_path("view_out");
    std::filesystem::create_directories(dir);
    const sim::PartialView v = sim::render_partial_view(sim::make_icosphere(10, 2), 1, 20);
    sim::write_partial_view(dir, v);
    std::ifstream j(dir / "view.json");
    const nlohmann::json meta = nlohmann::json::parse(j);
    CHECK(meta["format"] == "vtloc-synth-view/1");
    CHECK(meta["points"] == 20);
    CHECK(meta["camera"][0].get<double>() == v.camera[0]);
    std::ifstream x(dir / "view.xyz");
    std::string line;
    int rows = 0;
    while (std::getline(x, line))
        if (!line.empty() && line[0] != '#') ++rows;
    CHECK(rows == 20);
    CHECK(!std::filesystem::exists(dir / "view.xyz.tmp"));
}
