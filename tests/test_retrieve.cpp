// retrieve (topk + heatmap as one op): GPU against the CPU reference (indices and
// scores exactly, the heat-map at the default 1e-4 + 1e-4*|ref|, as in
// test_topk_heatmap.cpp), and bit for bit against the two ops run as separate
// nodes on the GPU, for the one-dispatch shader (K <= 16, no symmetry) and for
// the cases that fall back to the two ops' shaders (symmetry, K > 16, subgroup off).
#include <catch2/catch.hpp>
#include <cmath>

#include "engine/model/post.h"
#include "engine/ops/build.h"
#include "tests/run_both.h"

using namespace vtloc;
using vtloc::test::random_tensor;

namespace {

struct Case {
    int64_t B, M, P, D;
    int k;
    bool symmetry, subgroup;
};

void check_retrieve(const Case& c, uint32_t seed) {
    INFO("B " << c.B << " M " << c.M << " P " << c.P << " D " << c.D << " K " << c.k << (c.symmetry ? ", symmetry" : "")
              << (c.subgroup ? "" : ", subgroup off"));
    const Shape cs = c.B > 1 ? Shape{c.B, 3} : Shape{3};
    TensorMap in{{"c", random_tensor(cs, seed, -1.0f, 1.0f)}, {"cand", random_tensor({c.M, 3}, seed + 1, -1.0f, 1.0f)},
                 {"cloud", random_tensor({c.P, c.D}, seed + 2, -1.0f, 1.0f)}};
    // Coarse candidates: exact score ties, which must break to the lower index.
    for (float& v : in["cand"].data) v = std::round(v * 4.0f) / 4.0f;
    if (c.symmetry) in["sym"] = symmetry_transforms({0.1, 0.0, -0.1}, {0.2, 1.0, 0.1}, 3);
    // One op, and the same two ops as separate nodes.
    Graph fused, apart;
    for (Graph* g : {&fused, &apart}) {
        const int contact = g->input("c", cs), cand = g->input("cand", {c.M, 3}), cloud = g->input("cloud", {c.P, c.D});
        const int sym = c.symmetry ? g->input("sym", {3, 12}) : -1;
        if (g == &fused) {
            std::vector<int> o = ops::retrieve(*g, contact, cand, cloud, sym, c.k, "", c.subgroup);
            g->output(o[0], "index");
            g->output(o[1], "score");
            g->output(o[2], "heat");
        } else {
            std::vector<int> top = ops::topk(*g, contact, cand, c.k, "", c.subgroup);
            g->output(top[0], "index");
            g->output(top[1], "score");
            g->output(ops::heatmap(*g, cloud, cand, top[0], sym, "", c.subgroup), "heat");
        }
    }
    test::BothRuns r = test::run_both(fused, WeightStore{}, in);
    const Shape ks = c.B > 1 ? Shape{c.B, c.k} : Shape{c.k}, hs = c.B > 1 ? Shape{c.B, c.P} : Shape{c.P};
    REQUIRE(r.gpu.at("index").shape == ks);
    REQUIRE(r.gpu.at("heat").shape == hs);
    test::require_same_ints(r.gpu.at("index"), r.cpu.at("index"), "retrieve index");
    CHECK(r.gpu.at("score").data == r.cpu.at("score").data);
    test::require_close(r.gpu.at("heat"), r.cpu.at("heat"), test::Tolerance{}, "retrieve heat-map");
    TensorMap two = GpuExecutor(test::gpu(), apart, WeightStore{}).run(in);
    test::require_no_validation_messages();
    CHECK(r.gpu.at("index").ints() == two.at("index").ints());
    CHECK(r.gpu.at("score").data == two.at("score").data);
    CHECK(r.gpu.at("heat").data == two.at("heat").data);
}

}  // namespace

TEST_CASE("retrieve equals topk then heatmap, in one dispatch or two ops", "[op][retrieve]") {
    uint32_t seed = 60;
    for (bool subgroup : {true, false})
        for (const Case& c : {Case{1, 37, 1037, 6, 5, false, subgroup}, Case{1, 1, 1, 3, 1, false, subgroup},
                              Case{1, 2049, 513, 3, 16, false, subgroup}, Case{3, 301, 257, 6, 7, false, subgroup},
                              Case{1, 301, 513, 6, 5, true, subgroup}, Case{2, 100, 77, 3, 64, false, subgroup}})
            check_retrieve(c, seed++);
    // Scans past lavapipe's loop limit in one invocation take the two ops' shaders.
    check_retrieve({1, 100003, 1024, 6, 5, false, true}, seed++);
    check_retrieve({1, 64, 100000, 3, 5, false, true}, seed++);
}

TEST_CASE("retrieve refuses what topk and heatmap refuse", "[op][retrieve]") {
    Graph g;
    const int c = g.input("c", {3}), cand = g.input("cand", {4, 3}), cloud = g.input("cloud", {9, 6});
    REQUIRE_THROWS_WITH(ops::retrieve(g, c, cand, cloud, -1, 5), Catch::Contains("K = 5 exceeds the 4 candidates"));
    REQUIRE_THROWS_WITH(ops::retrieve(g, c, cand, g.input("flat", {9, 2}), -1, 2), Catch::Contains("cloud must be [P, D >= 3]"));
    REQUIRE_THROWS_WITH(ops::retrieve(g, c, cand, cloud, g.input("sym", {2, 11}), 2), Catch::Contains("symmetry maps must be"));
    REQUIRE_THROWS_WITH(g.add("retrieve", {c, cand}, {{"k", 1}}), Catch::Contains("inputs"));
}
