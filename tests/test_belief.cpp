// Multi-contact belief (SPEC 6): GPU against the CPU reference (double, log
// space) on random sequences, and a hand-made sequence whose single touch is
// ambiguous while the sequence with the known motion resolves it.
// Tolerance: the default 1e-4 + 1e-4*|ref| for the belief and the log belief;
// the GPU works in fp32 log space (measured max error ~1e-7 on the belief,
// ~2e-5 on log beliefs of magnitude ~100, M = 1000, T = 5).
#include <catch2/catch.hpp>

#include "base/error.h"
#include "engine/ops/build.h"
#include "tests/harness.h"

using namespace vtloc;
using vtloc::test::random_tensor;

namespace {

Graph belief_graph(int64_t M, int64_t T, const ops::Belief& b) {
    Graph g;
    std::vector<int> o = ops::belief(g, g.input("cand", {M, 3}), g.input("cp", {T, 3}), g.input("d", {T - 1, 3}), b);
    g.output(o[0], "belief");
    g.output(o[1], "log");
    return g;
}

TensorMap compare(const Graph& g, const TensorMap& in) {
    TensorMap want = run_cpu(g, WeightStore{}, in);
    GpuExecutor exec(test::gpu(), g, WeightStore{});
    TensorMap got = exec.run(in);
    test::require_no_validation_messages();
    test::require_close(got.at("belief"), want.at("belief"), {}, "belief");
    test::require_close(got.at("log"), want.at("log"), {}, "log belief");
    double sum = 0;
    for (float v : got.at("belief").data) sum += v;
    CHECK(std::abs(sum - 1.0) < 1e-5);
    return got;
}

int argmax(const HostTensor& t) { return int(std::max_element(t.data.begin(), t.data.end()) - t.data.begin()); }

}  // namespace

TEST_CASE("belief matches the CPU reference on random sequences", "[op][belief]") {
    struct Case { int64_t M, T; int window; };
    for (Case c : {Case{1, 1, 4}, Case{37, 1, 4}, Case{37, 2, 4}, Case{37, 6, 4}, Case{37, 5, 0}, Case{1000, 3, 4},
                   Case{301, 4, 2}}) {
        INFO("M " << c.M << " T " << c.T << " window " << c.window);
        HostTensor cand = random_tensor({c.M, 3}, uint32_t(c.M));
        HostTensor cp = random_tensor({c.T, 3}, uint32_t(c.T) + 5, -0.8f, 0.8f);
        HostTensor d = random_tensor({c.T - 1, 3}, 9, -0.1f, 0.1f);
        compare(belief_graph(c.M, c.T, {0.2, 0.05, c.window}),
                {{"cand", cand}, {"cp", cp}, {"d", d}});
    }
}

TEST_CASE("a touch sequence resolves what one touch leaves ambiguous", "[op][belief]") {
    // A (0) and E (4) are equally near the second touch; the motion d = (0, 0.4, 0)
    // from the first touch (equally near A' = 2 - d and B' = 3 - d) only fits A -> A'.
    HostTensor cand({7, 3}, {-.4f, 0, 0, .4f, 0, 0, -.4f, .4f, 0, .4f, .4f, 0, 0, .8f, 0, 0, -.8f, 0, .8f, .8f, .3f});
    HostTensor cp({2, 3}, {0, 0, 0, -.2f, .6f, 0});
    HostTensor d({1, 3}, {0, .4f, 0});
    // One touch (window 1): candidates 2 and 4 tie.
    HostTensor one = compare(belief_graph(7, 2, {.window = 1}), {{"cand", cand}, {"cp", cp}, {"d", d}}).at("belief");
    CHECK(std::abs(one.data[2] - one.data[4]) < 1e-6f);
    CHECK(one.data[2] > 0.3f);
    // The sequence: candidate 2 (A') holds nearly all the belief.
    HostTensor seq = compare(belief_graph(7, 2, {}), {{"cand", cand}, {"cp", cp}, {"d", d}}).at("belief");
    CHECK(argmax(seq) == 2);
    // weights_tools.post.multi_contact_belief on the same numbers (float64):
    test::require_close(seq, HostTensor({7}, {2.27780063e-16f, 4.17193688e-18f, 0.982013792f, 0.0179862079f,
                                              3.39698721e-15f, 1.16374737e-27f, 6.74803879e-27f}), {}, "post.py");
    test::require_close(one, HostTensor({7}, {0.00899161209f, 0.0001646871f, 0.490925517f, 0.00899161343f,
                                              0.490925591f, 1.85330773e-11f, 9.79265382e-07f}), {}, "post.py, window 1");
    CHECK(seq.data[2] > 0.95f);
    CHECK(seq.data[4] < 1e-6f);  // E: no candidate moves onto it
    // The first touch alone cannot tell A from B.
    HostTensor first = compare(belief_graph(7, 1, {}), {{"cand", cand}, {"cp", HostTensor({1, 3}, {0, 0, 0})},
                                                         {"d", HostTensor({0, 3})}}).at("belief");
    CHECK(std::abs(first.data[0] - first.data[1]) < 1e-6f);
}

TEST_CASE("belief rejects bad inputs", "[op][belief]") {
    Graph g;
    int cand = g.input("cand", {5, 3}), cp = g.input("cp", {3, 3}), d = g.input("d", {3, 3}), d2 = g.input("d2", {2, 3});
    int empty = g.input("e", {0, 3});
    REQUIRE_THROWS_WITH(ops::belief(g, cand, cp, d, {}), Catch::Contains("motions must be [T - 1, 3] = [2, 3]"));
    REQUIRE_THROWS_WITH(ops::belief(g, empty, cp, d2, {}), Catch::Contains("candidates must be [M > 0, 3]"));
    // Raw Params on purpose: Graph::add must refuse bad values, whoever builds the node.
    REQUIRE_THROWS_WITH(g.add("belief", {cand, cp, d2}, {{"sigma", 0}}), Catch::Contains("positive"));
    REQUIRE_THROWS_WITH(g.add("belief", {cand, cp, d2}, {{"window", -1}}), Catch::Contains("window"));
    Graph g2 = belief_graph(2, 1, {});
    REQUIRE_THROWS_WITH(run_cpu(g2, WeightStore{}, {{"cand", HostTensor({2, 3}, {0, 0, 0, 0, NAN, 0})},
                                                    {"cp", HostTensor({1, 3})}, {"d", HostTensor({0, 3})}}),
                        Catch::Contains("candidates hold NaN"));
}
