// group_linear's param pad (GroupLinear::skip_padding): a ball's padding rows (its
// free slots, which repeat its first index) are left out of the max and may stay
// unwritten in a plain output. The maxes must equal, bit for bit, the same layers
// without it (the rows left out repeat row 0) and the CPU reference within the
// default fp32 tolerance; a plain output's real rows must equal the reference's.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <set>
#include <string>

#include "base/error.h"
#include "engine/check/fault_injection.h"
#include "engine/check/graph_check.h"
#include "engine/check/op_selftest.h"
#include "engine/ops/build.h"
#include "engine/ops/common.h"
#include "tests/harness.h"
#include "tests/run_both.h"

using namespace vtloc;

namespace {

using In = ops::GroupLinear::Input;
using Hidden = ops::GroupLinear::Hidden;
using Weights = ops::GroupLinear::Weights;
using Tile = ops::GroupLinear::Tile;

// Rows j > 0 of a ball whose index is the ball's first.
std::vector<bool> padding_rows(const HostTensor& ball) {
    const int64_t S = ball.shape.at(0), NS = ball.shape.at(1);
    std::vector<bool> pad(size_t(S * NS), false);
    for (int64_t s = 0; s < S; ++s)
        for (int64_t j = 1; j < NS; ++j) pad[size_t(s * NS + j)] = ball.int_at(size_t(s * NS + j)) == ball.int_at(size_t(s * NS));
    return pad;
}

// A plain output's real rows (padding rows unspecified) against the reference's:
// [C, M], or [M, C] with point_major.
void require_real_rows_close(const HostTensor& got, const HostTensor& want, const std::vector<bool>& pad, bool point_major,
                             const std::string& what) {
    REQUIRE(got.shape == want.shape);
    REQUIRE(got.shape.size() == 2);
    const int64_t M = got.shape[point_major ? 0 : 1], C = got.shape[point_major ? 1 : 0];
    REQUIRE(M == int64_t(pad.size()));
    HostTensor a(got.shape), b(got.shape);
    for (int64_t k = 0; k < C; ++k)
        for (int64_t m = 0; m < M; ++m)
            if (!pad[size_t(m)]) {
                const size_t e = size_t(point_major ? m * C + k : k * M + m);
                a.data[e] = got.data[e], b.data[e] = want.data[e];
            }
    test::require_close(a, b, {}, what + " (real rows) against the CPU reference");
}

// The layer variants the tests sweep: every weight path on texel buffers, storage
// buffers, and the big-layer tile on the shuffle path of each. Layouts: the rows
// between layers channel-major (false) or point-major (true); both on each buffer
// path's default (shuffled weights, the device's tile), one each, taking turns,
// elsewhere: every layout meets every path, for a third fewer pipelines to compile.
// For the second shape (the defaults alone) the layouts take turns too: each pair
// of path and layout met on the first.
struct Variant {
    ops::BufferPath path;
    Weights weights;
    Tile tile;
    std::string suffix;  // of output names
    std::vector<bool> layouts;
    std::vector<Hidden> hidden;  // the kinds of hidden layer it runs
};
constexpr Hidden kHiddenKinds[] = {Hidden::None, Hidden::Gathered, Hidden::PerPoint};
struct PadSweep {
    // false: each buffer path's default only (shuffled weights, the device's tile),
    // for a second shape on the paths' code.
    bool all_weights = true;
    // Only the variants whose shader depends on the subgroup size
    // (test::subgroup_shader_variant), for the README's subgroup-4 run.
    bool subgroup_shader = false;
    // The big-layer tile on storage buffers too (the long suite; a CPU device
    // reads texel buffers, and these pipelines are the slowest to compile).
    bool big_on_storage = false;
    // -1: every variant runs each kind of hidden layer (the long suite). k >= 0: variant i
    // runs kind (k + i) % 3 alone (the README's command: a third of the pipelines), and a
    // case's shapes start at different k so that each kind meets each buffer path.
    int hidden_from = -1;
};
std::vector<Variant> variants(const PadSweep& sweep) {
    const bool all_weights = sweep.all_weights;
    std::vector<Variant> v;
    bool turn = false;
    for (ops::BufferPath path : ops::kBufferPaths)
        for (Weights wp : {Weights::Shuffle, Weights::Uniform, Weights::Storage})
            for (Tile tile : {Tile::Auto, Tile::Big8x32}) {
                if (sweep.subgroup_shader && !test::subgroup_shader_variant(path, wp)) continue;
                if (!test::sweep_takes_tile(path, tile, sweep.big_on_storage)) continue;
                if ((path == ops::BufferPath::Storage || !all_weights) && wp != Weights::Shuffle) continue;
                if (tile != Tile::Auto && (wp != Weights::Shuffle || !test::big_tiles_apply() || !all_weights)) continue;
                const bool both = all_weights && wp == Weights::Shuffle && tile == Tile::Auto;
                v.push_back({path, wp, tile,
                             std::string(".") + ops::path_name(path) + "." + std::to_string(int(wp)) +
                                 (tile == Tile::Auto ? "" : ".big8"),
                             both ? std::vector<bool>{false, true} : std::vector<bool>{turn},
                             sweep.hidden_from < 0 ? std::vector<Hidden>(std::begin(kHiddenKinds), std::end(kHiddenKinds))
                                                   : std::vector<Hidden>{kHiddenKinds[(size_t(sweep.hidden_from) + v.size()) % 3]}});
                if (!both) turn = !turn;
            }
    return v;
}

std::string infer_error(std::vector<TensorDesc> in, Params p) {
    try {
        find_op("group_linear").infer(in, p);
    } catch (const Error& e) {
        return e.what();
    }
    return "no error";
}

}  // namespace

namespace {

struct PadCase {
    int64_t S, ns;
    double radius;
    int64_t C1, C2, C3;
};

// ball padding skipped (pad) leaves every max exact: the cases given. Returns the
// kinds of hidden layer that ran (a once-per-variant sweep checks it met all three).
std::set<Hidden> padding_cases(std::initializer_list<PadCase> cases, const PadSweep& sweep = {}) {
    std::set<Hidden> hidden_run;
    const bool all_weights = sweep.all_weights, subgroup_shader = sweep.subgroup_shader;
    // Balls of 16 .. 128 around 8 .. 64 centres of 300 points: a small radius pads
    // most slots (whole subgroups of rows are padding), a large one few. Three
    // layers (the paper's shape), as the point encoder builds them: a gathered
    // layer (plain, or with layer one in registers from the row or per source point),
    // a plain rows layer between, a max. Every weight path, both buffer paths.
    for (PadCase c : cases) {  // 20: not a multiple of the row tiles
        const int64_t N = 300, K0 = 6;
        WeightStore w;
        w.add("w0", test::random_tensor({K0, c.C1}, 71, -0.5f, 0.5f));
        w.add("b0", test::random_tensor({c.C1}, 72, -0.2f, 0.2f));
        w.add("w1", test::random_tensor({c.C1, c.C2}, 73, -0.3f, 0.3f));
        w.add("b1", test::random_tensor({c.C2}, 74, -0.2f, 0.2f));
        w.add("w2", test::random_tensor({c.C2, c.C3}, 75, -0.3f, 0.3f));
        w.add("b2", test::random_tensor({c.C3}, 76, -0.2f, 0.2f));
        Graph g;
        const int x = g.input("cloud", {N, 6});
        std::vector<int> f = ops::fps(g, x, c.S);
        const int ball = ops::ball_query(g, x, f[1], c.radius, c.ns);
        g.output(ball, "ball");
        const int w0 = g.weight("w0", {K0, c.C1}), b0 = g.weight("b0", {c.C1}), w1 = g.weight("w1", {c.C1, c.C2}),
                  b1 = g.weight("b1", {c.C2}), w2 = g.weight("w2", {c.C2, c.C3}), b2 = g.weight("b2", {c.C3});
        std::vector<std::string> plain_names;
        for (const Variant& v : variants(sweep)) {
            const ops::BufferPath path = v.path;
            const Weights wp = v.weights;
            const Tile tile = v.tile;
            const std::string& on = v.suffix;
            ops::GroupLinear u_layer{In::Points, 3, false, 1, ops::kActNone, 0.01, path, wp};
            u_layer.point_major = true;
            const int u = ops::group_linear(g, {x, w0, b0, x}, u_layer);
            for (Hidden hidden : v.hidden)
                for (bool pad : {false, true})
                    for (bool pm : v.layouts) {  // rows between layers channel- or point-major
                    const std::string lay = pm ? ".pm" : "";
                    // Layer one (gathered rows: normals, then xyz less the centre) and two.
                    ops::GroupLinear first{In::Gather, 3, false, 1, ops::kActRelu, 0.01, path, wp, tile};
                    first.skip_padding = pad;
                    first.point_major = pm;
                    int h = -1;
                    if (hidden == Hidden::None) {
                        const int h0 = ops::group_linear(g, {x, f[1], ball, w0, b0, x}, first);
                        ops::GroupLinear two{In::Rows, 0, false, 1, ops::kActRelu, 0.01, path, wp, tile};
                        two.x_point_major = two.point_major = pm;
                        h = ops::group_linear(g, {h0, w1, b1}, two);  // a plain rows layer after a skipping one
                    } else {
                        first.hidden = hidden;
                        h = hidden == Hidden::Gathered ? ops::group_linear(g, {x, f[1], ball, w0, b0, w1, b1, x}, first)
                                                       : ops::group_linear(g, {u, f[1], ball, w0, w1, b1}, first);
                        if (pad) {
                            const std::string name = "plain." + std::to_string(int(hidden)) + lay + on;
                            g.output(h, name);
                            plain_names.push_back(name);
                        }
                    }
                    ops::GroupLinear last{In::Rows, 0, true, c.ns, ops::kActRelu, 0.01, path, wp, tile};
                    last.skip_padding = pad;
                    last.x_point_major = pm;
                    std::vector<int> in{h, w2, b2};
                    if (pad) in.push_back(ball);
                    g.output(ops::group_linear(g, in, last), std::string(pad ? "pad" : "full") + "." +
                                                                std::to_string(int(hidden)) + lay + on);
                    }
            // One gathered layer that is also the max.
            for (bool pad : {false, true}) {
                ops::GroupLinear one{In::Gather, 3, true, 1, ops::kActRelu, 0.01, path, wp, tile};
                one.skip_padding = pad;
                g.output(ops::group_linear(g, {x, f[1], ball, w0, b0, x}, one), std::string(pad ? "pad" : "full") + ".one" + on);
            }
        }
        INFO(c.S << " balls of " << c.ns << ", radius " << c.radius << ", widths " << c.C1 << ", " << c.C2 << ", " << c.C3);
        const test::BothRuns r = test::run_both(g, w, {{"cloud", test::random_tensor({N, 6}, 77)}});
        test::require_same_ints(r.gpu.at("ball"), r.cpu.at("ball"), "ball");
        const std::vector<bool> pad = padding_rows(r.cpu.at("ball"));
        int64_t padded = 0;
        for (size_t m = 0; m < pad.size(); ++m) padded += pad[m];
        INFO(padded << " of " << pad.size() << " rows are padding");
        if (c.radius < 1.0) CHECK(padded * 2 > int64_t(pad.size()));  // the case pads as meant
        int64_t maxes = 0, layout_twins = 0;
        for (const auto& [name, t] : r.gpu) {
            if (name.rfind("pad.", 0) != 0) continue;
            const std::string full = "full" + name.substr(3);
            INFO(name);
            CHECK(t.data == r.gpu.at(full).data);  // bit for bit: the rows left out repeat row 0
            test::require_close(t, r.cpu.at(name), {}, name + " against the CPU reference");
            test::require_close(r.gpu.at(full), r.cpu.at(full), {}, full + " against the CPU reference");
            if (const size_t at = name.find(".pm"); at != std::string::npos && r.gpu.count(name.substr(0, at) + name.substr(at + 3))) {
                CHECK(t.data == r.gpu.at(name.substr(0, at) + name.substr(at + 3)).data);  // the same sums in the same order
                ++layout_twins;
            }
            ++maxes;
        }
        // texel: 3 weight paths (+ the big tile on CPU devices); storage: the auto tile (+ the big one, long suite);
        // or the two defaults alone; the subgroup shader's: texel, shuffled weights, each tile
        // or the default. 3 hidden x each variant's row layouts + one
        const int64_t big = test::big_tiles_apply() ? 1 : 0,
                      big_storage = sweep.big_on_storage ? big : 0,
                      nv = subgroup_shader ? (all_weights ? 1 + big : 1) : (all_weights ? 3 + 1 + big + big_storage : 2);
        CHECK(int64_t(variants(sweep).size()) == nv);
        // Both layouts on the defaults with every weight path, one elsewhere and on the defaults alone.
        const int64_t both = all_weights ? (subgroup_shader ? 1 : 2) : 0;
        // Per variant: its hidden kinds x its layouts, plus the one-layer max; twins where it
        // runs both layouts; a plain output per hidden kind other than None and layout.
        int64_t want_maxes = 0, want_twins = 0, want_plain = 0, n_both = 0;
        for (const Variant& v : variants(sweep)) {
            const int64_t nh = int64_t(v.hidden.size()), nl = int64_t(v.layouts.size());
            const int64_t with_rows = nh - int64_t(std::count(v.hidden.begin(), v.hidden.end(), Hidden::None));
            want_maxes += nh * nl + 1, want_twins += nl == 2 ? nh : 0, want_plain += with_rows * nl, n_both += nl == 2;
            hidden_run.insert(v.hidden.begin(), v.hidden.end());
            CHECK(int64_t(v.hidden.size()) == (sweep.hidden_from < 0 ? 3 : 1));
        }
        CHECK(n_both == both);
        CHECK(maxes == want_maxes);
        CHECK(layout_twins == want_twins);
        for (const std::string& name : plain_names)  // [C2, M], or [M, C2] (.pm)
            require_real_rows_close(r.gpu.at(name), r.cpu.at(name), pad, name.find(".pm") != std::string::npos, name);
        CHECK(int64_t(plain_names.size()) == want_plain);

        // A max over rows whose padding holds poison (what a skipped block may hold):
        // left out, so it equals the max without pad over the clean rows (padding =
        // row 0 again) bit for bit, and the CPU reference on the poisoned rows.
        const HostTensor& ball_t = r.cpu.at("ball");
        const int64_t M = c.S * c.ns;
        HostTensor clean = test::random_tensor({c.C2, M}, 78), poisoned = clean;
        for (int64_t k = 0; k < c.C2; ++k)
            for (int64_t m = 0; m < M; ++m)
                if (pad[size_t(m)]) {
                    const size_t e = size_t(k * M + m);
                    clean.data[e] = clean.data[size_t(k * M + m / c.ns * c.ns)];
                    // Large, not NaN: a max would drop a NaN row by itself.
                    poisoned.data[e] = (m + k) % 2 == 0 ? 1e6f : -1e6f;
                }
        const HostTensor clean_pm = test::transposed(clean), poisoned_pm = test::transposed(poisoned);  // point-major
        Graph pg;
        const int xc = pg.input("clean", {c.C2, M}), xp = pg.input("poisoned", {c.C2, M}),
                  bi = pg.input("ball", ball_t.shape, ElemType::I32);
        const int xc_pm = pg.input("clean_pm", {M, c.C2}), xp_pm = pg.input("poisoned_pm", {M, c.C2});
        const int pw = pg.weight("w2", {c.C2, c.C3}), pb = pg.weight("b2", {c.C3});
        for (const Variant& v : variants(sweep)) {
            const ops::BufferPath path = v.path;
            const Weights wp = v.weights;
            const Tile tile = v.tile;
            const std::string& on = v.suffix;
            ops::GroupLinear last{In::Rows, 0, true, c.ns, ops::kActRelu, 0.01, path, wp, tile};
            pg.output(ops::group_linear(pg, {xc, pw, pb}, last), "clean" + on);
            last.skip_padding = true;
            pg.output(ops::group_linear(pg, {xp, pw, pb, bi}, last), "poisoned" + on);
            last.x_point_major = true;
            pg.output(ops::group_linear(pg, {xp_pm, pw, pb, bi}, last), "poisoned.pm" + on);
            last.skip_padding = false;
            pg.output(ops::group_linear(pg, {xc_pm, pw, pb}, last), "clean.pm" + on);
        }
        const test::BothRuns pr = test::run_both(pg, w, {{"clean", clean}, {"poisoned", poisoned}, {"ball", ball_t},
                                                         {"clean_pm", clean_pm}, {"poisoned_pm", poisoned_pm}});
        int64_t poisoned_maxes = 0;
        for (const auto& [name, t] : pr.gpu) {
            if (name.rfind("poisoned", 0) != 0) continue;
            INFO(name);
            CHECK(t.data == pr.gpu.at("clean" + name.substr(8)).data);
            test::require_close(t, pr.cpu.at(name), {}, name + " against the CPU reference");
            ++poisoned_maxes;
        }
        CHECK(poisoned_maxes == int64_t(variants(sweep).size()) * 2);
    }
    return hidden_run;
}

// The README command's sweeps: each variant one kind of hidden layer, the kinds taking
// turns over the variants and starting elsewhere on the second shape; all three must run.
void padding_quick(bool subgroup_shader) {
    std::set<Hidden> run = padding_cases({PadCase{19, 20, 0.3, 12, 37, 33}}, PadSweep{true, subgroup_shader, false, 0});
    const std::set<Hidden> second =
        padding_cases({PadCase{6, 128, 0.4, 64, 96, 128}}, PadSweep{false, subgroup_shader, false, 2});
    run.insert(second.begin(), second.end());
    CHECK(run.size() == 3);
}

}  // namespace

TEST_CASE("ball padding skipped (pad) leaves every max exact", "[op][group_linear][sweep]") {
    // Every path and layout (the big tile on texel buffers; on storage buffers in the
    // long suite) on a shape that is mostly padding, with odd widths and a
    // ball length that is not a multiple of the row tiles; balls of 128 around 6
    // centres on each buffer path's default, one row layout each (64 in the long
    // suite, every path and both layouts). Each variant one kind of hidden layer
    // here, every kind on every variant in the long suite.
    padding_quick(false);
}

TEST_CASE("ball padding skipped (pad) by the subgroup shader leaves every max exact", "[op][group_linear][subgroup_sweep]") {
    // The sweep above on the variants whose shader depends on the subgroup size (votes,
    // pooled chunks: texel buffers, shuffled weights), for the README's subgroup-4 run.
    padding_quick(true);
}

namespace {
// The full-size shapes, one list for both sweeps.
void padding_full_size(const PadSweep& sweep) {
    padding_cases({PadCase{37, 32, 0.25, 16, 20, 33}, PadCase{64, 128, 0.4, 64, 96, 128}, PadCase{8, 16, 1.5, 8, 12, 8},
                   PadCase{19, 40, 0.3, 12, 37, 16}, PadCase{23, 20, 0.3, 12, 20, 16}},
                  sweep);
}
}  // namespace

TEST_CASE("ball padding skipped (pad) leaves every max exact, at full size", "[long][group_linear]") {
    padding_full_size(PadSweep{true, false, true});
}

TEST_CASE("ball padding skipped (pad) by the subgroup shader leaves every max exact, at full size",
          "[long][group_linear][subgroup_sweep]") {
    // The case above on the subgroup shader's variants, for the long suite's subgroup-4 run.
    padding_full_size(PadSweep{true, true, true});
}

TEST_CASE("pad = 1 and x_point_major = 1 name what they need", "[op][group_linear]") {
    const TensorDesc x{{3, 8}}, w{{3, 4}}, b{{4}};
    CHECK(infer_error({x, w, b, TensorDesc{{2, 4}, ElemType::I32}}, {{"max", 1}, {"group", 4}, {"pad", 1}}) == "no error");
    CHECK_THAT(infer_error({x, w, b}, {{"pad", 1}}), Catch::Contains("pad = 1 needs ball rows (in = 1) or a max"));
    CHECK_THAT(infer_error({x, w, b}, {{"max", 1}, {"group", 4}, {"pad", 1}}), Catch::Contains("takes 4 inputs, got 3"));
    CHECK_THAT(infer_error({x, w, b, TensorDesc{{4, 2}, ElemType::I32}}, {{"max", 1}, {"group", 4}, {"pad", 1}}),
               Catch::Contains("ball [4, 2] must be [2, 4]: one index per row"));
    CHECK_THAT(infer_error({x, w, b, TensorDesc{{2, 4}}}, {{"max", 1}, {"group", 4}, {"pad", 1}}),
               Catch::Contains("input 3 has the wrong element type"));
    CHECK(infer_error({TensorDesc{{10, 6}}, TensorDesc{{2, 3}}, TensorDesc{{2, 4}, ElemType::I32}, TensorDesc{{3, 4}},
                       TensorDesc{{4}}},
                      {{"in", 1}, {"pad", 1}, {"point_major", 1}}) == "no error");  // a point-major plain output
    CHECK_THAT(infer_error({TensorDesc{{10, 6}}, TensorDesc{{2, 3}}, TensorDesc{{2, 4}, ElemType::I32}, TensorDesc{{3, 4}},
                            TensorDesc{{4}}},
                           {{"in", 1}, {"x_point_major", 1}}),
               Catch::Contains("x_point_major = 1 is for a previous layer's rows (in = 0)"));
    CHECK_THAT(infer_error({TensorDesc{{8, 5}}, w, b}, {{"x_point_major", 1}}),
               Catch::Contains("weight [3, 4] must be input-major [5, out]"));  // x [M = 8, K = 5]
    CHECK_THAT(infer_error({TensorDesc{{8}}, w, b}, {{"x_point_major", 1}}), Catch::Contains("x must be point-major [M, K], got [8]"));
    CHECK(infer_error({TensorDesc{{8, 3}}, w, b, TensorDesc{{2, 4}, ElemType::I32}},
                      {{"max", 1}, {"group", 4}, {"pad", 1}, {"x_point_major", 1}}) == "no error");
}

namespace {

// w0 [6, 16], b0, w1 [16, 24], b1: a hidden first layer and a gathering layer
// (the point encoder's pair), random from seeds `seed` to `seed` + 3.
WeightStore two_layers(uint32_t seed) {
    WeightStore w;
    w.add("w0", test::random_tensor({6, 16}, seed, -0.5f, 0.5f));
    w.add("b0", test::random_tensor({16}, seed + 1, -0.2f, 0.2f));
    w.add("w1", test::random_tensor({16, 24}, seed + 2, -0.3f, 0.3f));
    w.add("b1", test::random_tensor({24}, seed + 3, -0.2f, 0.2f));
    return w;
}

}  // namespace

TEST_CASE("the node-by-node check compares a skipping layer's real rows only", "[op][group_linear][check]") {
    // The point encoder's pair: a gathering layer (layer one in registers) that
    // skips padding, then the max; vtloc check must pass it, and must still see a
    // wrong real row.
    const int64_t N = 200, S = 16, NS = 64;
    WeightStore w = two_layers(81);
    w.add("w2", test::random_tensor({24, 32}, 85, -0.3f, 0.3f));
    w.add("b2", test::random_tensor({32}, 86, -0.2f, 0.2f));
    for (bool pm : {false, true}) {  // the rows between channel- or point-major
    INFO((pm ? "point-major" : "channel-major") << " rows");
    Graph g;
    const int x = g.input("cloud", {N, 6});
    std::vector<int> f = ops::fps(g, x, S);
    const int ball = ops::ball_query(g, x, f[1], 0.3, NS);
    ops::GroupLinear first{In::Gather, 3, false, 1, ops::kActRelu};
    first.hidden = Hidden::Gathered, first.skip_padding = true, first.point_major = pm;
    const int h = ops::group_linear(g, {x, f[1], ball, g.weight("w0", {6, 16}), g.weight("b0", {16}), g.weight("w1", {16, 24}),
                                        g.weight("b1", {24}), x},
                                    first, "plain");
    ops::GroupLinear last{In::Rows, 0, true, NS, ops::kActRelu};
    last.skip_padding = true, last.x_point_major = pm;
    g.output(ops::group_linear(g, {h, g.weight("w2", {24, 32}), g.weight("b2", {32}), ball}, last, "max"), "max");
    const TensorMap in{{"cloud", test::random_tensor({N, 6}, 87)}};
    const check::GraphCheck ok = check::check_graph(test::gpu(), g, w, in);
    CHECK(ok.ok());
    // A wrong real row of the plain output fails the check at that node; a wrong
    // padding row (unspecified) does not.
    Graph gb = g;
    gb.output(ball, "ball");
    const HostTensor balls = run_cpu(gb, w, in).at("ball");
    int64_t pad_row = -1;
    for (int64_t m = 0; m < S * NS && pad_row < 0; ++m)
        if (m % NS != 0 && balls.int_at(size_t(m)) == balls.int_at(size_t(m / NS * NS))) pad_row = m;
    REQUIRE(pad_row > 0);
    for (int64_t row : {int64_t(0), pad_row}) {
        INFO("row " << row << " of the plain output corrupted");
        check::testing::set_fault("plain", [&](HostTensor& t) { t.data[size_t(pm ? row * 24 : row)] += 1.0f; });  // channel 0
        const check::GraphCheck r = check::check_graph(test::gpu(), g, w, in);
        check::testing::clear_fault();
        if (row == 0) {
            CHECK_FALSE(r.ok());
            REQUIRE(r.first_failure >= 0);
            CHECK(r.nodes[size_t(r.first_failure)].node == "plain");
        } else {
            CHECK(r.ok());
        }
    }
    }
    test::require_no_validation_messages();
}

TEST_CASE("the vote shader leaves padding blocks unwritten", "[op][group_linear]") {
    // What the skipping is for: on the shuffle path (it has the subgroup vote), a
    // gathering layer with pad writes fewer rows. Its outputs are the graph's only
    // values of their kind (an arena could hand a skipping layer the memory of an
    // every-row twin, whose rows would look written), so some padding rows hold
    // other values than the reference's; the real rows hold the reference's.
    const rt::DeviceInfo& d = test::gpu().info();
    if (ops::group_linear_weight_path(d, 16, 24, true, Weights::Shuffle, 0) != Weights::Shuffle) {
        WARN("this device has no subgroup shuffles and votes: nothing is skipped here, nothing to test");
        return;
    }
    const int64_t N = 300, S = 64, NS = 128;
    WeightStore w = two_layers(91);
    Graph g;
    const int x = g.input("cloud", {N, 6});
    std::vector<int> f = ops::fps(g, x, S);
    const int ball = ops::ball_query(g, x, f[1], 0.4, NS);
    g.output(ball, "ball");
    const int w0 = g.weight("w0", {6, 16}), b0 = g.weight("b0", {16}), w1 = g.weight("w1", {16, 24}), b1 = g.weight("b1", {24});
    ops::GroupLinear layer{In::Gather, 3, false, 1, ops::kActRelu};
    layer.hidden = Hidden::Gathered, layer.skip_padding = true;
    g.output(ops::group_linear(g, {x, f[1], ball, w0, b0, w1, b1, x}, layer), "plain");
    layer.point_major = true;  // the same, as [M, C]
    g.output(ops::group_linear(g, {x, f[1], ball, w0, b0, w1, b1, x}, layer), "plain.pm");
    const test::BothRuns r = test::run_both(g, w, {{"cloud", test::random_tensor({N, 6}, 95)}});
    const std::vector<bool> pad = padding_rows(r.cpu.at("ball"));
    for (bool pm : {false, true}) {
    INFO((pm ? "point-major" : "channel-major") << " output");
    const std::string name = pm ? "plain.pm" : "plain";
    const HostTensor &got = r.gpu.at(name), &want = r.cpu.at(name);
    const int64_t M = S * NS, C = 24;
    REQUIRE(got.shape == (pm ? Shape{M, C} : Shape{C, M}));
    int64_t padded = 0, unwritten = 0, wrong_real = 0;
    for (int64_t m = 0; m < M; ++m) {
        bool differs = false;
        for (int64_t k = 0; k < C; ++k) {
            const size_t e = size_t(pm ? m * C + k : k * M + m);
            const float a = got.data[e], b = want.data[e];
            differs = differs || !(std::fabs(a - b) <= 1e-4f + 1e-4f * std::fabs(b));
        }
        padded += pad[size_t(m)];
        (pad[size_t(m)] ? unwritten : wrong_real) += differs;
    }
    INFO(padded << " of " << M << " rows are padding, " << unwritten << " of them left unwritten");
    CHECK(wrong_real == 0);
    CHECK(unwritten * 4 > padded);  // most of them: 64 balls of 8 rows a block, 8 balls to a subgroup
    }
}

TEST_CASE("balls of very different lengths in one subgroup pool their chunks exactly", "[op][group_linear]") {
    // check::uneven_balls: a subgroup of 4 or 8 of its balls has far fewer chunks
    // than lanes x its longest ball (the vote shader pools them); its last 8 balls
    // are equally long (one lane per ball stays); ball 11 repeats its first index
    // mid-ball, real rows after it.
    // The maxes must match the CPU reference, and bit for bit the same layers
    // without pad; a plain output's real rows must match the reference, pooled
    // (CPU devices) or in row blocks (GPUs: param row_blocks). Each variant runs in
    // a graph of its own: in one graph the arena could give a layer the memory of
    // a twin with the same values, and rows it failed to write would look right.
    const int64_t P = 300, S = 40, NS = 64;
    const HostTensor ball = check::uneven_balls(S, NS, P);
    const std::vector<bool> pad = padding_rows(ball);
    WeightStore w = two_layers(101);
    w.add("w2", test::random_tensor({24, 40}, 105, -0.3f, 0.3f));
    w.add("b2", test::random_tensor({40}, 106, -0.2f, 0.2f));
    const TensorMap inputs{{"cloud", test::random_tensor({P, 6}, 107)}, {"centres", test::random_tensor({S, 3}, 108)}, {"ball", ball}};
    // The layers of one variant: the gathering layer (layer one in registers) and the max.
    auto run = [&](Tile tile, bool pm, bool skip, bool rb) {
        Graph g;
        const int x = g.input("cloud", {P, 6}), c = g.input("centres", {S, 3}), bi = g.input("ball", {S, NS}, ElemType::I32);
        ops::GroupLinear first{In::Gather, 3, false, 1, ops::kActRelu, 0.01, ops::BufferPath::Texel, Weights::Shuffle, tile};
        first.hidden = Hidden::Gathered, first.skip_padding = skip, first.point_major = pm, first.row_blocks = rb;
        const int h = ops::group_linear(g, {x, c, bi, g.weight("w0", {6, 16}), g.weight("b0", {16}), g.weight("w1", {16, 24}),
                                            g.weight("b1", {24}), x},
                                        first);
        g.output(h, "plain");
        ops::GroupLinear last{In::Rows, 0, true, NS, ops::kActRelu, 0.01, ops::BufferPath::Texel, Weights::Shuffle, tile};
        last.skip_padding = skip, last.x_point_major = pm;
        std::vector<int> in{h, g.weight("w2", {24, 40}), g.weight("b2", {40})};
        if (skip) in.push_back(bi);
        g.output(ops::group_linear(g, in, last), "max");
        return test::run_both(g, w, inputs);
    };
    // The big tile CPU devices take (8 x 32; the 16 x 32 one no device picks compiles slowest).
    for (Tile tile : {Tile::Auto, Tile::Big8x32})
        for (bool pm : {false, true}) {
            if (tile != Tile::Auto && !test::big_tiles_apply()) continue;
            const test::BothRuns full = run(tile, pm, false, false);
            for (bool rb : {false, true}) {
                INFO((tile == Tile::Auto ? "auto tile" : "8 x 32") << (pm ? ", point-major" : ", channel-major")
                                                                   << (rb ? ", row blocks" : ", pooled"));
                const test::BothRuns r = run(tile, pm, true, rb);
                test::require_close(r.gpu.at("max"), r.cpu.at("max"), {}, "max against the CPU reference");
                CHECK(r.gpu.at("max").data == full.gpu.at("max").data);  // the rows left out repeat row 0
                require_real_rows_close(r.gpu.at("plain"), r.cpu.at("plain"), pad, pm, "the plain output");
            }
        }
    // One gathering layer that is also the max.
    Graph g;
    const int x = g.input("cloud", {P, 6}), c = g.input("centres", {S, 3}), bi = g.input("ball", {S, NS}, ElemType::I32);
    for (bool skip : {false, true}) {
        ops::GroupLinear one{In::Gather, 3, true, 1, ops::kActRelu, 0.01, ops::BufferPath::Texel, Weights::Shuffle};
        one.skip_padding = skip;
        g.output(ops::group_linear(g, {x, c, bi, g.weight("w0", {6, 16}), g.weight("b0", {16}), x}, one), skip ? "pad" : "full");
    }
    const test::BothRuns r = test::run_both(g, w, inputs);
    test::require_close(r.gpu.at("pad"), r.cpu.at("pad"), {}, "one layer with pad against the CPU reference");
    CHECK(r.gpu.at("pad").data == r.gpu.at("full").data);
}
