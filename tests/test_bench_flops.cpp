// bench::node_flops: the FLOP counts behind every GFLOP/s the benches print,
// checked against counts written out by hand for each op and group_linear form.
#include <catch2/catch.hpp>

#include "bench/flops.h"
#include "engine/ops/build.h"
#include "engine/ops/common.h"
#include "tests/harness.h"

using namespace vtloc;
using GL = ops::GroupLinear;

TEST_CASE("bench node_flops counts each GEMM-like node's multiply-adds", "[bench]") {
    Graph g;
    const int img = g.input("img", {2, 3, 10, 12}), seq = g.input("seq", {2, 5, 7});
    const int cm = g.input("cm", {8, 20}), pm = g.input("pm", {20, 8});  // K = 8, M = 20, both layouts
    const int cloud = g.input("cloud", {30, 6});
    ops::Conv2d c;
    c.pad_h = c.pad_w = 1;
    ops::conv2d(g, img, g.weight("cw", {4, 3, 3, 3}), -1, -1, c, "conv");
    ops::linear(g, seq, g.weight("lw", {6, 7}), g.weight("lb", {6}), ops::kActNone, 0.01, "fc");
    const int w8 = g.weight("w8", {8, 12}), b12 = g.weight("b12", {12});
    ops::group_linear(g, {cm, w8, b12}, GL{}, "rows_cm");
    GL xpm;
    xpm.x_point_major = true;
    ops::group_linear(g, {pm, w8, b12}, xpm, "rows_pm");

    const std::vector<int> f = ops::fps(g, cloud, 5, "fps");
    const int ball = ops::ball_query(g, cloud, f[1], 0.5, 8, "ball");  // 40 rows, some of them padding
    const int w0 = g.weight("w0", {6, 8}), b0 = g.weight("b0", {8});
    GL gather;
    gather.input = GL::Input::Gather, gather.feat_begin = 3;  // the normals: K = 3 + 3
    ops::group_linear(g, {cloud, f[1], ball, w0, b0, cloud}, gather, "gather");
    GL hid = gather;
    hid.hidden = GL::Hidden::Gathered;
    ops::group_linear(g, {cloud, f[1], ball, w0, b0, w8, b12, cloud}, hid, "hidden_gathered");
    GL points;
    points.input = GL::Input::Points, points.feat_begin = 3, points.point_major = true;
    const int u = ops::group_linear(g, {cloud, w0, b0, cloud}, points, "per_point");
    hid.hidden = GL::Hidden::PerPoint;
    ops::group_linear(g, {u, f[1], ball, w0, w8, b12}, hid, "hidden_per_point");
    GL skip = gather;
    skip.skip_padding = true, skip.max = true, skip.group = 8;
    ops::group_linear(g, {cloud, f[1], ball, w0, b0, cloud}, skip, "gather_max_pad");
    GL rows_max;
    rows_max.max = true, rows_max.group = 8, rows_max.skip_padding = true, rows_max.x_point_major = true;
    const int h = g.input("h", {40, 8});
    ops::group_linear(g, {h, w8, b12, ball}, rows_max, "rows_max_pad");

    const std::map<std::string, HostTensor> balls =
        bench::ball_indices(g, WeightStore{}, {{"cloud", test::random_tensor({30, 6}, 71, -1.f, 1.f)}});
    REQUIRE(balls.count("ball") == 1);
    const HostTensor& b = balls.at("ball");
    REQUIRE(b.shape == Shape{5, 8});
    double real = 0;  // rows that are not SPEC 2's padding (a slot past 0 repeating slot 0)
    for (int64_t s = 0; s < 5; ++s)
        for (int64_t j = 0; j < 8; ++j) real += j == 0 || b.int_at(size_t(s * 8 + j)) != b.int_at(size_t(s * 8));
    REQUIRE(real > 5);
    REQUIRE(real < 40);  // the case must have padding to skip

    for (bool with_balls : {false, true}) {
        INFO("balls given: " << with_balls);
        const std::map<std::string, double> f = bench::node_flops(g, with_balls ? balls : std::map<std::string, HostTensor>{});
        const double rows = with_balls ? real : 40;
        const std::map<std::string, double> want{
            {"conv", 2.0 * 2 * 10 * 12 * (4 * 3 * 3 * 3)},  // every output, Cout * Cin * KH * KW each
            {"fc", 2.0 * 10 * 6 * 7},                       // 2 x 5 rows
            {"rows_cm", 2.0 * 20 * 8 * 12},
            {"rows_pm", 2.0 * 20 * 8 * 12},  // M from dim 0, not dim 1
            {"gather", 2.0 * 40 * 6 * 8},
            {"hidden_gathered", 2.0 * 40 * (6 * 8 + 8 * 12)},  // layer one counted once per row
            {"per_point", 2.0 * 30 * 6 * 8},
            {"hidden_per_point", 2.0 * 40 * 8 * 12},  // layer one counts in per_point
            {"gather_max_pad", 2.0 * rows * 6 * 8},
            {"rows_max_pad", 2.0 * rows * 8 * 12},
        };
        CHECK(f.size() == want.size());  // fps and ball query count nothing
        for (const auto& [name, flops] : want) {
            INFO(name);
            REQUIRE(f.count(name) == 1);
            CHECK(f.at(name) == flops);
        }
    }
}
