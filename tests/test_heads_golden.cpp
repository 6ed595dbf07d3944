// The ILU and MCR heads, fed the golden F^t and F^p, reproduce the PyTorch
// reference's c_1..c_N and c^p. Goldens are float64 rounded to float32; the
// engine works in float32 through a few Linear layers per iteration, so the
// default 1e-4 + 1e-4*|ref| holds.
#include <catch2/catch.hpp>

#include "engine/model/heads.h"
#include "tests/golden.h"

using namespace vtloc;

namespace {

struct HeadsCase {
    WeightStore weights;
    test::Golden golden;
    Graph graph;
    TensorMap inputs;
};

HeadsCase load_case(const std::string& name) {
    WeightStore w = WeightStore::load(test::require_golden_file(test::goldens_dir(), name + ".safetensors"));
    test::Golden gold(test::require_golden_file(test::goldens_dir(), name + ".golden.safetensors"));
    int64_t C = config_of(w).C;
    HostTensor ft = gold.f32("tactile.feature"), fp = gold.f32("point.feature");
    REQUIRE(ft.shape == Shape{C});
    ft.shape = fp.shape = {1, C};
    return {std::move(w), std::move(gold), Graph{}, {{"ft", ft}, {"fp", fp}}};
}

}  // namespace

TEST_CASE("ILU iterations match the PyTorch golden (vtloc-tiny)", "[heads][golden]") {
    HeadsCase hc = load_case("vtloc-tiny");
    const ModelConfig cfg = config_of(hc.weights);
    int64_t C = cfg.C;
    int iters = cfg.ilu_iters;
    REQUIRE(hc.golden.shape("ilu.c") == Shape{iters, 3});
    Graph& g = hc.graph;
    IluOutputs ilu = build_ilu(g, hc.weights, g.input("ft", {1, C}), g.input("fp", {1, C}),
                               g.input("iters", {1}, ElemType::I32), iters);
    g.output(ilu.c, "c");
    g.output(ilu.contact, "contact");
    hc.inputs["iters"] = ilu_iters_input(iters, iters);
    TensorMap out = test::run_gpu_and_compare(g, hc.weights, hc.inputs);
    hc.golden.compare("ilu.c", out.at("c"));
    hc.golden.compare("contact", out.at("contact"));
}

TEST_CASE("ILU iteration count is bounded", "[heads]") {
    Graph g;
    int ft = g.input("ft", {1, 4}), fp = g.input("fp", {1, 4}), n = g.input("n", {1}, ElemType::I32);
    REQUIRE_THROWS_WITH(build_ilu(g, WeightStore{}, ft, fp, n, 65), Catch::Contains("0..64"));
    REQUIRE_THROWS_WITH(ilu_iters_input(5, 4), Catch::Contains("0..4"));
    CHECK(ilu_iters_input(0, 0).int_at(0) == 0);
}

TEST_CASE("MCR head matches the PyTorch golden (vtloc-mcr-tiny)", "[heads][golden]") {
    HeadsCase hc = load_case("vtloc-mcr-tiny");
    int64_t C = config_of(hc.weights).C;
    Graph& g = hc.graph;
    g.output(build_mcr(g, hc.weights, config_of(hc.weights), g.input("ft", {1, C}), g.input("fp", {1, C})), "c");
    TensorMap out = test::run_gpu_and_compare(g, hc.weights, hc.inputs);
    hc.golden.compare("contact", HostTensor({3}, out.at("c").data));
}
