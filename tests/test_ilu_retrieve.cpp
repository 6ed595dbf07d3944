// ilu_retrieve: the ILU with top-K and heat-map as its epilogue. Against the CPU
// references of ilu and retrieve (the ILU's default tolerance, 1e-4 + 1e-4|ref|;
// top-K indices exact) and against the two ops' own dispatches (indices exact,
// floats at the same tolerance), one dispatch where it fuses and two where it
// cannot (symmetry maps, K > 16, an ILU workgroup narrower than a subgroup).
#include <catch2/catch.hpp>


#include "engine/model/heads.h"
#include "engine/ops/build.h"
#include "engine/ops/ilu_math.h"
#include "tests/harness.h"
#include "tests/ilu_test_util.h"

using namespace vtloc;
using vtloc::test::random_ilu;
using vtloc::test::random_tensor;

namespace {

struct Case {
    int64_t B = 1, C = 64, H = 32, M = 301, P = 1037, D = 6, K = 5, T = 0;
    int iters = 16, wave = 1;
};

struct Built {
    Graph g;
    TensorMap inputs;
};

// Candidates and cloud near the origin, where the ILU's contacts land (its
// outputs are sums of small head outputs), so the top-K is not decided by a tie.
Built build(const WeightStore& w, const Case& c, bool fuse) {
    Built r;
    Graph& g = r.g;
    std::vector<int> in = test::ilu_graph_inputs(g, w, c.B, c.C);
    const int sym = c.T > 0 ? g.input("sym", {c.T, 12}) : -1;
    std::vector<int> out = ops::ilu_retrieve(g, in, c.iters, g.input("cand", {c.M, 3}), g.input("cloud", {c.P, c.D}), sym,
                                             c.K, "ilu", fuse, c.wave);
    const char* names[] = {"c", "contact", "index", "score", "heat"};
    for (int i = 0; i < 5; ++i) g.output(out[size_t(i)], names[i]);
    r.inputs = {{"ft", random_tensor({c.B, c.C}, 3, -2.0f, 2.0f)},
                {"fp", random_tensor({1, c.C}, 4, -2.0f, 2.0f)},
                {"iters", ilu_iters_input(c.iters, c.iters)},
                {"cand", random_tensor({c.M, 3}, 5, -0.5f, 0.5f)},
                {"cloud", random_tensor({c.P, c.D}, 6, -0.5f, 0.5f)}};
    if (c.T > 0) {
        HostTensor s({c.T, 12});
        for (int64_t t = 0; t < c.T; ++t)  // rotations about z by 2 pi t / T
            for (int i = 0; i < 12; ++i) {
                const double a = 6.283185307179586 * double(t) / double(c.T);
                const double m[12] = {std::cos(a), -std::sin(a), 0, 0, std::sin(a), std::cos(a), 0, 0, 0, 0, 1, 0};
                s.data[size_t(t * 12 + i)] = float(m[i]);
            }
        r.inputs["sym"] = s;
    }
    return r;
}

size_t dispatches(const GpuExecutor& e) { return e.sequence().dispatch_log().size(); }

}  // namespace

TEST_CASE("ilu_retrieve matches the CPU references, fused and apart, and the two agree", "[op][ilu_retrieve][ilu][retrieve]") {
    const uint32_t sg = test::gpu().info().subgroup_size;
    std::vector<Case> cases;
    cases.push_back(Case{});                                               // the lite model's head shape
    cases.push_back(Case{3, 20, 12, 37, 41, 3, 7, 0, 9, 1});               // a batch; odd cloud and candidate counts
    cases.push_back(Case{2, 64, 64, 1000, 513, 6, 16, 0, 5, int(2 * sg)});  // ILU over two subgroups, K = 16
    cases.push_back(Case{1, 16, 8, 5, 3, 3, 5, 0, 0, 1});                   // N = 0, every candidate kept
    // The register-resident ILU fuses: the default takes it on CPU devices only.
    for (Case& c : cases) c.wave = c.wave == 1 ? int(sg) : c.wave;
    for (const Case& c : cases) {
        INFO("B " << c.B << " C " << c.C << " H " << c.H << " M " << c.M << " P " << c.P << " K " << c.K << " N "
                  << c.iters << " wave " << c.wave);
        WeightStore w = random_ilu(c.C, c.H, uint32_t(c.C + c.M));
        Built fused = build(w, c, true), apart = build(w, c, false);
        TensorMap a = test::run_gpu_and_compare(fused.g, w, fused.inputs);
        TensorMap b = test::run_gpu_and_compare(apart.g, w, apart.inputs);
        // Not bit for bit: a driver may round the ILU's sums differently in the
        // two shaders (lavapipe does at subgroup size 4 with two subgroups).
        CHECK(a.at("index").ints() == b.at("index").ints());
        for (const char* n : {"c", "contact", "score", "heat"}) test::require_close(a.at(n), b.at(n), {}, n);
        GpuExecutor ef(test::gpu(), fused.g, w), ea(test::gpu(), apart.g, w);
        CHECK(dispatches(ef) == 1);
        CHECK(dispatches(ea) == 2);
        CHECK(ef.sequence().dispatch_log().at(0).shader == "ilu_retrieve");
    }
}

TEST_CASE("ilu_retrieve records the two ops' dispatches where it cannot fuse", "[op][ilu_retrieve][ilu][retrieve]") {
    const uint32_t sg = test::gpu().info().subgroup_size;
    std::vector<std::pair<Case, std::string>> cases{
        {Case{2, 20, 12, 37, 41, 3, 5, 3, 6, 1}, "symmetry maps"},
        {Case{1, 20, 12, 300, 41, 3, 17, 0, 6, 1}, "K 17"},
    };
    if (sg >= 4) cases.push_back({Case{1, 20, 12, 37, 41, 3, 5, 0, 6, int(sg / 2)}, "an ILU workgroup of half a subgroup"});
    for (const auto& [c, why] : cases) {
        INFO(why);
        WeightStore w = random_ilu(c.C, c.H, 9);
        Built f = build(w, c, true);
        test::run_gpu_and_compare(f.g, w, f.inputs);
        GpuExecutor e(test::gpu(), f.g, w);
        std::vector<std::string> shaders;
        for (const auto& d : e.sequence().dispatch_log()) shaders.push_back(d.shader);
        CHECK(shaders.size() >= 2);
        for (const std::string& s : shaders) CHECK(s != "ilu_retrieve");
    }
}

TEST_CASE("ilu_retrieve keeps the ILU and retrieval apart where together they outrun the loop budget",
          "[op][ilu_retrieve][ilu][retrieve]") {
    // One invocation runs the ILU's loops and both scans, and lavapipe's limiter
    // counts them together (engine/ops/common.h). At subgroup size 8 the ILU at
    // N = 64 (C 64, H 32) takes ~13,400 iterations and retrieval on 24,000
    // candidates and points ~54,100: each fits 60,000, the sum does not. With
    // 2,000 of each the sum fits and the node is one dispatch.
    const uint32_t sg = test::gpu().info().subgroup_size;
    WeightStore w = random_ilu(64, 32, 5);
    for (int64_t n : {2000, 24000}) {
        INFO(n << " candidates and points, subgroup " << sg);
        Case c{1, 64, 32, n, n, 3, 5, 0, 64, int(sg)};
        Built f = build(w, c, true);
        test::run_gpu_and_compare(f.g, w, f.inputs);  // the heat-map's last points included
        GpuExecutor e(test::gpu(), f.g, w);
        bool fused = false;
        for (const auto& d : e.sequence().dispatch_log()) fused = fused || d.shader == "ilu_retrieve";
        if (n == 2000) CHECK(fused);
        if (n == 24000 && sg <= 8) CHECK(!fused);  // wider subgroups take fewer iterations
    }
}

TEST_CASE("the ILU's default shader: register-resident on CPU devices, the shared-memory one on GPUs",
          "[op][ilu_retrieve][ilu]") {
    rt::DeviceInfo d = test::gpu().info();
    d.type = VK_PHYSICAL_DEVICE_TYPE_CPU;
    CHECK(ops::ilu_math::wave_by_default(d));
    for (auto t : {VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU, VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU}) {
        d.type = t;
        CHECK_FALSE(ops::ilu_math::wave_by_default(d));
    }
    // On this device, the head as the model builds it (wave 1): the shader the rule names.
    const rt::DeviceInfo& here = test::gpu().info();
    WeightStore w = random_ilu(64, 32, 11);
    Built f = build(w, Case{}, true);
    test::run_gpu_and_compare(f.g, w, f.inputs);
    GpuExecutor e(test::gpu(), f.g, w);
    std::vector<std::string> shaders;
    for (const auto& r : e.sequence().dispatch_log()) shaders.push_back(r.shader);
    INFO(here.name);
    if (ops::ilu_math::wave_by_default(here)) {
        CHECK(shaders == std::vector<std::string>{"ilu_retrieve"});
    } else {
        REQUIRE(!shaders.empty());
        CHECK((shaders.front() == "ilu_subgroup" || shaders.front() == "ilu"));
    }
}
