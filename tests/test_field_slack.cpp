// field_slack (engine/ops/field_slack.cpp): the grid's log fields widened by
// odometry slack. GPU against the CPU reference on random fields and neighbour
// tables of odd sizes with fixed seeds, then the closed form on a hand-made table.
// Tolerance 0: each output is a max over the same fp32 subtractions of the same
// products (`precise` in the shader, no contraction on the host), with no sum.
#include <catch2/catch.hpp>

#include <cmath>

#include "engine/check/op_selftest.h"
#include "engine/executor.h"
#include "engine/ops/build.h"
#include "tests/harness.h"

using namespace vtloc;

namespace {

Graph slack_graph(int64_t F, int64_t S, int64_t KN, int64_t NS) {
    Graph g;
    g.output(ops::field_slack(g, g.input("fields", {F, S * NS}), g.input("nb", {S, KN, 3}), g.input("w", {F, 2}), NS), "out");
    return g;
}

}  // namespace

TEST_CASE("field_slack matches the CPU reference", "[op][pose][field_slack]") {
    struct Shape { int64_t F, S, KN, NS; };
    for (const Shape sh : {Shape{1, 1, 1, 1}, Shape{3, 7, 5, 36}, Shape{2, 331, 12, 36}, Shape{5, 61, 3, 7}, Shape{1, 1031, 16, 12}}) {
        INFO("F " << sh.F << " S " << sh.S << " KN " << sh.KN << " NS " << sh.NS);
        const uint32_t seed = uint32_t(sh.S * 31 + sh.F);
        HostTensor w({sh.F, 2});
        for (int64_t f = 0; f < sh.F; ++f) {  // every mix of the two slacks on and off
            w.data[size_t(2 * f)] = f % 2 == 0 ? 0.35f + 0.1f * float(f) : 0.0f;
            w.data[size_t(2 * f + 1)] = f % 3 != 1 ? 2.5f : 0.0f;
        }
        HostTensor fields = test::random_tensor({sh.F, sh.S * sh.NS}, seed, -30.0f, 0.0f);
        fields.data[0] = -INFINITY;  // a field may hold -inf (a touch no hypothesis explains)
        const TensorMap in{{"fields", fields}, {"nb", check::random_slack_neighbours(sh.S, sh.KN, sh.NS, seed + 1)}, {"w", w}};
        const TensorMap got = test::run_gpu_and_compare(slack_graph(sh.F, sh.S, sh.KN, sh.NS), WeightStore{}, in, {0, 0});
        for (size_t i = 0; i < fields.data.size(); ++i) CHECK(got.at("out").data[i] >= fields.data[i]);  // a max with itself
    }
}

TEST_CASE("field_slack takes the best neighbour less its prior, and nothing where the widths are 0", "[op][pose][field_slack]") {
    // Three samples, four spins. Sample 0's neighbours: sample 2 at d^2 = 4 with spin offset 1, then sample 1
    // at d^2 = 1 with offset 0. Field 0 has both slacks; field 1 none.
    const int64_t S = 3, NS = 4, KN = 3, H = S * NS;
    HostTensor nb({S, KN, 3}, std::vector<float>(size_t(S * KN * 3), -1.0f));
    const float rows[2][3] = {{2, 4, 1}, {1, 1, 0}};
    for (int k = 0; k < 2; ++k)
        for (int i = 0; i < 3; ++i) nb.data[size_t(k * 3 + i)] = rows[k][i];
    HostTensor fields({2, H}, std::vector<float>(size_t(2 * H), -20.0f));
    for (int f = 0; f < 2; ++f) {
        fields.data[size_t(f * H + 2 * NS + 3)] = 0.0f;  // sample 2, spin 3: reached from sample 0's spin 2
        fields.data[size_t(f * H + 1 * NS + 0)] = -1.0f; // sample 1, spin 0: from sample 0's spin 0
        fields.data[size_t(f * H + 0 * NS + 1)] = -5.0f; // sample 0, spin 1: a spin step from spins 0 and 2
    }
    HostTensor w({2, 2}, {0.5f, 0.25f, 0.0f, 0.0f});
    const TensorMap got = test::run_gpu_and_compare(slack_graph(2, S, KN, NS), WeightStore{},
                                                    {{"fields", fields}, {"nb", nb}, {"w", w}}, {0, 0});
    const std::vector<float>& o = got.at("out").data;
    const float step = float(2 * M_PI / 4), spin_pen = 0.25f * (step * step);
    CHECK(o[2] == std::max(-20.0f, std::max(-5.0f - spin_pen, 0.0f - 0.5f * 4.0f)));  // sample 2's peak, less 2
    CHECK(o[0] == std::max(-1.0f - 0.5f, -5.0f - spin_pen));                           // sample 1, less 0.5
    CHECK(o[1] == -5.0f);                                                              // its own value is best
    CHECK(o[3] == -20.0f);                                                             // nothing better near
    for (int64_t h = 0; h < H; ++h) CHECK(o[size_t(H + h)] == fields.data[size_t(H + h)]);  // field 1: unchanged
}

TEST_CASE("field_slack ends a row at an entry out of range, and an infinite width at d^2 = 0 costs nothing", "[op][pose][field_slack]") {
    // A table from a user may hold anything: an entry out of range (index >= S, a NaN, a spin offset
    // outside 0..NS-1, a negative d^2) must end its row as -1 does, never read past the field.
    const int64_t S = 2, NS = 3, KN = 2, H = S * NS;
    const HostTensor fields({1, H}, {-9.0f, -9.0f, -9.0f, 0.0f, -1.0f, -2.0f}), inf_width({1, 2}, {INFINITY, 0.0f});
    const auto run = [&](const HostTensor& nb, const HostTensor& w) {
        return test::run_gpu_and_compare(slack_graph(1, S, KN, NS), WeightStore{}, {{"fields", fields}, {"nb", nb}, {"w", w}}, {0, 0})
            .at("out").data;
    };
    const float bad[][3] = {{2, 1, 0}, {NAN, 1, 0}, {1, 1, 3}, {1, 1, -1}, {1, -1, 0}, {1e9f, 1, 0}};
    for (const auto& b : bad) {
        INFO("entry " << b[0] << " " << b[1] << " " << b[2]);
        HostTensor nb({S, KN, 3}, std::vector<float>(size_t(S * KN * 3), -1.0f));
        for (int i = 0; i < 3; ++i) nb.data[size_t(i)] = b[i];   // sample 0: the bad entry first,
        const float after[3] = {1, 0, 0};                        // then a good one it hides
        for (int i = 0; i < 3; ++i) nb.data[size_t(3 + i)] = after[i];
        const std::vector<float> got = run(nb, inf_width);
        for (int64_t h = 0; h < H; ++h) CHECK(got[size_t(h)] == fields.data[size_t(h)]);
    }
    // The good entry alone: sample 1 at d^2 = 0 with a_t = inf takes sample 1's values at no cost (not NaN).
    HostTensor nb({S, KN, 3}, std::vector<float>(size_t(S * KN * 3), -1.0f));
    nb.data[0] = 1, nb.data[1] = 0, nb.data[2] = 0;
    const std::vector<float> got = run(nb, inf_width);
    for (int64_t j = 0; j < NS; ++j) CHECK(got[size_t(j)] == fields.data[size_t(NS + j)]);
    // Subnormals count as 0 on both sides (a GPU may flush them): a d^2 of 1e-40 costs nothing at
    // a_t = inf, and a width of 1e-40 is off (the field unchanged, though its neighbour is better).
    nb.data[1] = 1e-40f;
    const std::vector<float> sub = run(nb, inf_width);
    for (int64_t j = 0; j < NS; ++j) CHECK(sub[size_t(j)] == fields.data[size_t(NS + j)]);
    const std::vector<float> off = run(nb, HostTensor({1, 2}, {1e-40f, 1e-40f}));
    for (int64_t h = 0; h < H; ++h) CHECK(off[size_t(h)] == fields.data[size_t(h)]);
}

TEST_CASE("field_slack refuses bad shapes by name", "[pose][field_slack]") {
    Graph g;
    const int f = g.input("f", {2, 12}), w = g.input("w", {2, 2});
    CHECK_THROWS_WITH(ops::field_slack(g, f, g.input("nb", {3, 2, 2}), w, 4), Catch::Contains("neighbours must be [S > 0, KN > 0, 3]"));
    CHECK_THROWS_WITH(ops::field_slack(g, f, g.input("nb2", {4, 2, 3}), w, 4), Catch::Contains("fields must be [F > 0, S * NS] = [F, 16]"));
    CHECK_THROWS_WITH(ops::field_slack(g, f, g.input("nb3", {3, 2, 3}), g.input("w3", {3, 2}), 4),
                      Catch::Contains("widths must be [F, 2]"));
    CHECK_THROWS_WITH(ops::field_slack(g, f, g.input("nb4", {3, 2, 3}), w, 0), Catch::Contains("n_spin must be an integer"));
}
