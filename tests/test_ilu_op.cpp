// The fused ILU op: GPU against the CPU reference (double) with random weights at
// odd sizes, the iteration count changed between runs of one recorded graph, and
// N = 0. Tolerance: the default 1e-4 + 1e-4*|ref|; c accumulates N head outputs
// computed in fp32, measured max error ~1e-6 (see the report).
#include <catch2/catch.hpp>

#include "base/error.h"
#include "engine/model/heads.h"
#include "engine/ops/build.h"
#include "tests/harness.h"
#include "tests/ilu_test_util.h"

using namespace vtloc;
using vtloc::test::random_ilu;
using vtloc::test::random_tensor;

namespace {

struct IluGraph {
    Graph g;
    TensorMap inputs;
};

// The fused head, or (stepped) one ilu_step dispatch per iteration.
IluGraph ilu_graph(const WeightStore& w, int64_t C, int max_iters, uint32_t seed, bool stepped = false) {
    IluGraph r;
    auto build = stepped ? build_ilu_stepped : build_ilu;
    IluOutputs o = build(r.g, w, r.g.input("ft", {1, C}), r.g.input("fp", {1, C}),
                         r.g.input("iters", {1}, ElemType::I32), max_iters);
    r.g.output(o.contact, "contact");
    if (max_iters > 0) r.g.output(o.c, "c");
    r.inputs = {{"ft", random_tensor({1, C}, seed, -2.0f, 2.0f)}, {"fp", random_tensor({1, C}, seed + 1, -2.0f, 2.0f)},
                {"iters", ilu_iters_input(max_iters, max_iters)}};
    return r;
}

}  // namespace

TEST_CASE("ilu matches the CPU reference at odd sizes", "[op][ilu]") {
    struct Case { int64_t C, H; int iters; };
    for (Case c : {Case{1, 1, 1}, Case{37, 19, 7}, Case{16, 16, 64}, Case{128, 64, 16}, Case{301, 33, 3}, Case{512, 64, 4}}) {
        INFO("C " << c.C << " H " << c.H << " N " << c.iters);
        WeightStore w = random_ilu(c.C, c.H, uint32_t(c.C));
        IluGraph ig = ilu_graph(w, c.C, c.iters, 5);
        test::run_gpu_and_compare(ig.g, w, ig.inputs);
    }
}

TEST_CASE("ilu matches the CPU reference with 1, 4, 8 and 16 lanes per row, both ways of summing", "[op][ilu]") {
    // The shader's row groups: 1 lane (no partial sums) up to 16 (coalesced rows).
    // Where the device has subgroup shuffles, groups that fit a subgroup sum by
    // shuffles (lavapipe, subgroup size 8: 4 and 8 lanes; size 4: 4 lanes), the
    // others through shared memory; `subgroup` off forces shared memory.
    const int64_t C = 37, H = 19;
    WeightStore w = random_ilu(C, H, 11);
    for (auto [lanes, subgroup] : {std::pair{1, true}, {4, true}, {8, true}, {8, false}, {16, true}}) {
        INFO("lanes " << lanes << ", subgroup sums allowed " << subgroup);
        Graph g;
        std::vector<int> out = ops::ilu(g, test::ilu_graph_inputs(g, w, 1, C), 5, "", lanes, subgroup);
        g.output(out[0], "c");
        test::run_gpu_and_compare(g, w, {{"ft", random_tensor({1, C}, 1, -2.0f, 2.0f)},
                                         {"fp", random_tensor({1, C}, 2, -2.0f, 2.0f)}, {"iters", ilu_iters_input(5, 5)}});
    }
}

namespace {

// The fused op on explicit inputs, with the shader variant chosen by `wave`.
std::vector<int> ilu_nodes(Graph& g, const WeightStore& w, int64_t B, int64_t C, int max_iters, int wave) {
    return ops::ilu(g, test::ilu_graph_inputs(g, w, B, C), max_iters, "", 0, true, wave);
}

}  // namespace

TEST_CASE("ilu's register-resident shader matches the CPU reference, in one subgroup and across several", "[op][ilu]") {
    // wave = the subgroup size: h lives in registers and blocks move by shuffles;
    // 2 and 4 times it: the same shader passes blocks through shared memory. Sizes
    // cover a lane with no block (C = 4), several blocks per lane and a last
    // block held by only some lanes (C = 20, H = 12 at 8 lanes).
    const uint32_t sg = test::gpu().info().subgroup_size;
    struct Case { int64_t C, H; int iters; };
    for (Case c : {Case{4, 4, 3}, Case{20, 12, 9}, Case{64, 64, 16}, Case{128, 64, 40}, Case{200, 64, 16}}) {
        WeightStore w = random_ilu(c.C, c.H, uint32_t(c.C) + 7);
        for (uint32_t wave : {sg, 2 * sg, 4 * sg}) {
            INFO("C " << c.C << " H " << c.H << " workgroup " << wave << " (subgroup " << sg << ")");
            Graph g;
            std::vector<int> out = ilu_nodes(g, w, 1, c.C, c.iters, int(wave));
            g.output(out[0], "c");
            g.output(out[1], "contact");
            test::run_gpu_and_compare(g, w, {{"ft", random_tensor({1, c.C}, 3, -2.0f, 2.0f)},
                                             {"fp", random_tensor({1, c.C}, 4, -2.0f, 2.0f)},
                                             {"iters", ilu_iters_input(c.iters, c.iters)}});
        }
    }
}

TEST_CASE("ilu's register-resident shader runs a batch, each row bit-identical to it alone", "[op][ilu]") {
    const int64_t C = 64, H = 32, B = 4;
    const int n = 6;
    WeightStore w = random_ilu(C, H, 41);
    const HostTensor ft = random_tensor({B, C}, 42, -2.0f, 2.0f), fp = random_tensor({1, C}, 43, -2.0f, 2.0f);
    Graph g;
    std::vector<int> all = ilu_nodes(g, w, B, C, n, int(test::gpu().info().subgroup_size));
    g.output(all[1], "contact");
    TensorMap got = test::run_gpu_and_compare(g, w, {{"ft", ft}, {"fp", fp}, {"iters", ilu_iters_input(n, n)}});
    for (int64_t b = 0; b < B; ++b) {
        Graph g1;
        std::vector<int> one = ilu_nodes(g1, w, 1, C, n, int(test::gpu().info().subgroup_size));
        g1.output(one[1], "contact");
        HostTensor row({1, C});
        std::copy_n(ft.data.begin() + b * C, C, row.data.begin());
        TensorMap alone = GpuExecutor(test::gpu(), g1, w).run({{"ft", row}, {"fp", fp}, {"iters", ilu_iters_input(n, n)}});
        for (int j = 0; j < 3; ++j) CHECK(got.at("contact").data[size_t(b * 3 + j)] == alone.at("contact").data[size_t(j)]);
    }
}

TEST_CASE("ilu refuses a forced register-resident shader where it cannot run, by name", "[op][ilu]") {
    WeightStore w = random_ilu(37, 19, 2);  // C not a multiple of 4
    Graph g;
    std::vector<int> out = ilu_nodes(g, w, 1, 37, 3, 16);
    g.output(out[1], "contact");
    REQUIRE_THROWS_WITH(GpuExecutor(test::gpu(), g, w), Catch::Contains("divisible by 4"));
    WeightStore w2 = random_ilu(16, 8, 2);
    Graph g2;
    std::vector<int> out2 = ilu_nodes(g2, w2, 1, 16, 3, 12);  // not a power of two
    g2.output(out2[1], "contact");
    REQUIRE_THROWS_WITH(GpuExecutor(test::gpu(), g2, w2), Catch::Contains("power-of-two"));
    // A scan longer than a CPU driver lets one invocation's loops run (ops/common.h).
    // At 64 iterations (the most) C = 256 is over the budget for subgroup sizes up
    // to 16, and 512 for 8 to 128; at 4, 512 holds too many rows per lane.
    const int sg = int(test::gpu().info().subgroup_size);
    const int64_t C3 = sg <= 16 ? 256 : 512;
    WeightStore w3 = random_ilu(C3, 64, 2);
    Graph g3;
    std::vector<int> out3 = ilu_nodes(g3, w3, 1, C3, 64, sg);
    g3.output(out3[1], "contact");
    REQUIRE_THROWS_WITH(GpuExecutor(test::gpu(), g3, w3), Catch::Contains("loop iterations"));
}

TEST_CASE("ilu runs a batch of states in one dispatch, each row as if alone", "[op][ilu]") {
    const int64_t C = 37, H = 19, B = 5;
    const int max_iters = 9;
    WeightStore w = random_ilu(C, H, 21);
    Graph g;
    const int fp = g.input("fp", {1, C}), iters = g.input("iters", {1}, ElemType::I32);
    const int ft_all = g.input("ft", {B, C});
    IluOutputs all = build_ilu(g, w, ft_all, fp, iters, max_iters);
    CHECK(g.value(all.c).shape == Shape{B, max_iters, 3});
    CHECK(g.value(all.contact).shape == Shape{B, 3});
    g.output(all.c, "c");
    g.output(all.contact, "contact");
    for (int64_t b = 0; b < B; ++b) {  // the same rows through single-state ILUs in the same graph
        IluOutputs one = build_ilu(g, w, ops::rows(g, ft_all, b, 1), fp, iters, max_iters);
        g.output(one.contact, std::string("contact").append(std::to_string(b)));
    }
    TensorMap got = test::run_gpu_and_compare(g, w, {{"ft", random_tensor({B, C}, 31, -2.0f, 2.0f)},
                                                     {"fp", random_tensor({1, C}, 32, -2.0f, 2.0f)},
                                                     {"iters", ilu_iters_input(7, max_iters)}});
    for (int64_t b = 0; b < B; ++b)  // one workgroup per state runs the single-state code: bit-identical
        for (int j = 0; j < 3; ++j)
            CHECK(got.at("contact").data[size_t(b * 3 + j)] == got.at(std::string("contact").append(std::to_string(b))).data[size_t(j)]);
}

TEST_CASE("ilu takes N at run time: one recorded graph, N = 7, 2, 0", "[op][ilu]") {
    const int64_t C = 45, H = 21;
    const int nmax = 7;
    WeightStore w = random_ilu(C, H, 3);
    IluGraph ig = ilu_graph(w, C, nmax, 9);
    GpuExecutor exec(test::gpu(), ig.g, w);
    HostTensor full_c;
    for (int n : {7, 2, 0}) {
        INFO("N = " << n);
        ig.inputs["iters"] = ilu_iters_input(n, nmax);
        TensorMap want = run_cpu(ig.g, w, ig.inputs), got = exec.run(ig.inputs);
        test::require_no_validation_messages();
        test::require_close(got.at("c"), want.at("c"), {}, "c");
        test::require_close(got.at("contact"), want.at("contact"), {}, "contact");
        if (n == nmax) full_c = got.at("c");
        // The first n rows are c_1..c_n (a prefix of the longer run), the rest zeros.
        for (int r = 0; r < nmax; ++r)
            for (int j = 0; j < 3; ++j) {
                float v = got.at("c").data[size_t(3 * r + j)];
                if (r < n) CHECK(v == full_c.data[size_t(3 * r + j)]);
                else CHECK(v == 0.0f);
            }
        if (n == 0) CHECK(got.at("contact").data == std::vector<float>{0, 0, 0});
    }
}

TEST_CASE("ilu with max_iters = 0 gives c^p = 0", "[op][ilu]") {
    WeightStore w = random_ilu(8, 4, 1);
    IluGraph ig = ilu_graph(w, 8, 0, 2);
    TensorMap out = test::run_gpu_and_compare(ig.g, w, ig.inputs);
    CHECK(out.at("contact").data == std::vector<float>{0, 0, 0});
}

TEST_CASE("ilu rejects bad shapes and iteration counts", "[op][ilu]") {
    WeightStore w = random_ilu(8, 4, 1);
    Graph g;
    int ft = g.input("ft", {1, 8}), fp = g.input("fp", {1, 9}), n = g.input("n", {1}, ElemType::I32);
    REQUIRE_THROWS_WITH(build_ilu(g, w, ft, fp, n, 4), Catch::Contains("F^p is [1, 9]"));
    int nf = g.input("nf", {1});
    REQUIRE_THROWS_WITH(build_ilu(g, w, ft, ft, nf, 4), Catch::Contains("I32 [1]"));
    IluGraph ig = ilu_graph(w, 8, 4, 2);
    ig.inputs["iters"] = HostTensor::from_ints({1}, {5});
    REQUIRE_THROWS_WITH(run_cpu(ig.g, w, ig.inputs), Catch::Contains("outside 0..4"));
}

TEST_CASE("ilu_step (one dispatch per iteration) matches its CPU reference and the fused ilu", "[op][ilu][ilu_step]") {
    // Stepped and fused differ only in where fp32 rounding happens (the CPU
    // stepped reference rounds h, gx and c to fp32 between steps like the
    // shader), so they are compared with the default tolerance too.
    struct Case { int64_t C, H; int nmax; };
    for (Case c : {Case{1, 1, 1}, Case{37, 19, 7}, Case{128, 64, 16}}) {
        INFO("C " << c.C << " H " << c.H << " max_iters " << c.nmax);
        WeightStore w = random_ilu(c.C, c.H, uint32_t(c.C) + 3);
        IluGraph st = ilu_graph(w, c.C, c.nmax, 7, true), fu = ilu_graph(w, c.C, c.nmax, 7);
        GpuExecutor exec(test::gpu(), st.g, w);
        for (int n : {c.nmax, c.nmax / 2, 0}) {
            INFO("N = " << n);
            st.inputs["iters"] = fu.inputs["iters"] = ilu_iters_input(n, c.nmax);
            TensorMap want = run_cpu(st.g, w, st.inputs), got = exec.run(st.inputs), fused = run_cpu(fu.g, w, fu.inputs);
            test::require_no_validation_messages();
            for (const char* name : {"c", "contact"}) {
                test::require_close(got.at(name), want.at(name), {}, name);
                test::require_close(want.at(name), fused.at(name), {}, name);
            }
            for (size_t i = size_t(3 * n); i < got.at("c").data.size(); ++i) CHECK(got.at("c").data[i] == 0.0f);
        }
    }
}

TEST_CASE("ilu_step rejects a missing state and steps out of range", "[op][ilu]") {
    WeightStore w = random_ilu(8, 4, 1);
    IluGraph ig = ilu_graph(w, 8, 3, 2, true);
    std::vector<int> in = ig.g.nodes().back().inputs;
    // Raw Params on purpose: Graph::add must refuse a step out of range.
    REQUIRE_THROWS_WITH(ig.g.add("ilu_step", in, {{"max_iters", 3}, {"step", 3}}), Catch::Contains("step must be"));
    in.back() = in[0];  // F^t where step 1 needs the state of step 0
    REQUIRE_THROWS_WITH(ops::ilu_step(ig.g, in, 3, 1), Catch::Contains("state of step 0"));
    REQUIRE_THROWS_WITH(build_ilu_stepped(ig.g, w, in[0], in[1], in[2], 0), Catch::Contains("max_iters >= 1"));
}
