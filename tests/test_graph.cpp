// The executor end to end: a 3-layer MLP read from a safetensors file the test
// writes, run on lavapipe and on the CPU references, with memory reuse.
#include <catch2/catch.hpp>

#include "base/error.h"
#include "engine/ops/build.h"
#include "engine/ops/common.h"
#include "engine/safetensors.h"
#include "tests/harness.h"

using namespace vtloc;
using vtloc::test::random_tensor;

namespace {

// x[B,24] -> linear 24->64 + relu -> linear 64->48, leaky -> concat with x ->
// linear 72->10 -> tanh, plus a residual-style add of two branches.
Graph mlp_graph(int64_t batch) {
    Graph g;
    int x = g.input("x", {batch, 24});
    using ops::kActNone;
    int h1 = ops::linear(g, x, g.weight("mlp.0.weight", {64, 24}), g.weight("mlp.0.bias", {64}), kActNone, 0.01, "fc0");
    int a1 = ops::activation(g, ops::kActRelu, h1, 0.01, "relu0");
    int h2 = ops::linear(g, a1, g.weight("mlp.2.weight", {48, 64}), g.weight("mlp.2.bias", {48}), kActNone, 0.01, "fc2");
    int a2 = ops::activation(g, ops::kActLeaky, h2, 0.01, "leaky2");
    int cat = ops::concat(g, {a2, x}, "cat");
    int h3 = ops::linear(g, cat, g.weight("mlp.4.weight", {10, 72}), g.weight("mlp.4.bias", {10}), kActNone, 0.01, "fc4");
    int y = ops::activation(g, ops::kActTanh, h3, 0.01, "tanh4");
    int gate = ops::activation(g, ops::kActSigmoid, h3, 0.01, "gate");
    int mixed = ops::binary(g, ops::Binary::Mul, y, gate, "mix");
    g.output(ops::binary(g, ops::Binary::Add, mixed, g.weight("mlp.4.bias", {10}), "out"), "y");
    g.output(a1, "hidden");
    return g;
}

std::string write_mlp_file(const std::string& name) {
    std::vector<TensorBlob> t;
    auto add = [&](const std::string& n, Shape s, uint32_t seed, float scale) {
        t.push_back(TensorBlob::f32(n, s, random_tensor(s, seed, -scale, scale).data));
    };
    add("mlp.0.weight", {64, 24}, 1, 0.2f);
    add("mlp.0.bias", {64}, 2, 0.2f);
    add("mlp.2.weight", {48, 64}, 3, 0.125f);
    add("mlp.2.bias", {48}, 4, 0.125f);
    add("mlp.4.weight", {10, 72}, 5, 0.12f);
    add("mlp.4.bias", {10}, 6, 0.12f);
    std::string path = test::temp_path(name);
    write_safetensors(path, t, {{"vtloc.config", R"({"name": "mlp-test"})"}});
    return path;
}

}  // namespace

TEST_CASE("an MLP graph from a safetensors file runs equal on GPU and CPU", "[graph]") {
    WeightStore w = WeightStore::load(write_mlp_file("mlp.safetensors"));
    CHECK(w.config()["name"] == "mlp-test");
    for (int64_t batch : {1, 5, 333}) {
        Graph g = mlp_graph(batch);
        TensorMap in{{"x", random_tensor({batch, 24}, 100 + uint32_t(batch), -2.f, 2.f)}};
        TensorMap out = test::run_gpu_and_compare(g, w, in);
        CHECK(out.at("y").shape == Shape{batch, 10});
        CHECK(out.at("hidden").shape == Shape{batch, 64});
    }
}

TEST_CASE("intermediates share arena memory", "[graph]") {
    WeightStore w = WeightStore::load(write_mlp_file("mlp-arena.safetensors"));
    Graph g = mlp_graph(200);
    GpuExecutor exec(test::gpu(), g, w);
    const MemoryPlan& plan = exec.memory_plan();
    INFO("arena " << plan.arena_bytes << " bytes, tensors " << plan.total_bytes << " bytes");
    CHECK(plan.arena_bytes < plan.total_bytes);
    // No two values that are alive at once may overlap: the run must stay correct.
    TensorMap in{{"x", random_tensor({200, 24}, 7)}};
    TensorMap want = run_cpu(g, w, in);
    TensorMap got = exec.run(in);
    test::require_no_validation_messages();
    test::require_close(got.at("y"), want.at("y"), {}, "y");
    test::require_close(got.at("hidden"), want.at("hidden"), {}, "hidden");
}

TEST_CASE("a recorded graph is resubmitted with new inputs", "[graph]") {
    WeightStore w = WeightStore::load(write_mlp_file("mlp-resubmit.safetensors"));
    Graph g = mlp_graph(3);
    GpuExecutor exec(test::gpu(), g, w);
    for (uint32_t seed : {1u, 2u, 3u}) {
        TensorMap in{{"x", random_tensor({3, 24}, seed)}};
        test::require_close(exec.run(in).at("y"), run_cpu(g, w, in).at("y"), {}, "y");
    }
    test::require_no_validation_messages();
}

TEST_CASE("memory plan never overlaps values that are alive together", "[graph]") {
    Graph g = mlp_graph(17);
    auto order = g.topo_order();
    MemoryPlan plan = plan_memory(g, order, 64);
    // Recompute lifetimes independently and check every pair.
    const auto& vals = g.values();
    std::vector<int> first(vals.size(), 1 << 30), last(vals.size(), -1);
    for (size_t i = 0; i < vals.size(); ++i)
        if (vals[i].kind == ValueKind::Input) first[i] = last[i] = -1;
    for (size_t pos = 0; pos < order.size(); ++pos) {
        for (int o : g.nodes()[size_t(order[pos])].outputs) first[size_t(o)] = last[size_t(o)] = int(pos);
        for (int in : g.nodes()[size_t(order[pos])].inputs) last[size_t(in)] = std::max(last[size_t(in)], int(pos));
    }
    for (auto& [n, id] : g.outputs()) last[size_t(id)] = 1 << 30;
    for (size_t a = 0; a < vals.size(); ++a)
        for (size_t b = a + 1; b < vals.size(); ++b) {
            if (plan.offset[a] < 0 || plan.offset[b] < 0) continue;
            bool alive_together = first[a] <= last[b] && first[b] <= last[a];
            int64_t ea = plan.offset[a] + numel(vals[a].shape) * 4, eb = plan.offset[b] + numel(vals[b].shape) * 4;
            bool overlap = plan.offset[a] < eb && plan.offset[b] < ea;
            INFO(vals[a].name << " and " << vals[b].name);
            CHECK(!(alive_together && overlap));
        }
}

TEST_CASE("topological order puts producers first", "[graph]") {
    Graph g = mlp_graph(2);
    auto order = g.topo_order();
    REQUIRE(order.size() == g.nodes().size());
    std::vector<int> pos_of_value(g.values().size(), -1);
    for (size_t p = 0; p < order.size(); ++p)
        for (int o : g.nodes()[size_t(order[p])].outputs) pos_of_value[size_t(o)] = int(p);
    for (size_t p = 0; p < order.size(); ++p)
        for (int in : g.nodes()[size_t(order[p])].inputs) CHECK(pos_of_value[size_t(in)] < int(p));
}

TEST_CASE("graph inputs are checked by name and shape", "[graph]") {
    WeightStore w = WeightStore::load(write_mlp_file("mlp-inputs.safetensors"));
    Graph g = mlp_graph(4);
    REQUIRE_THROWS_WITH(run_cpu(g, w, {}), Catch::Contains("'x' was not given"));
    REQUIRE_THROWS_WITH(run_cpu(g, w, {{"x", HostTensor({4, 23})}}),
                        Catch::Contains("shape [4, 23], expected [4, 24]"));
    REQUIRE_THROWS_WITH(run_cpu(g, w, {{"x", HostTensor({4, 24})}, {"z", HostTensor({1})}}),
                        Catch::Contains("'z' is not an input"));
    GpuExecutor exec(test::gpu(), g, w);
    REQUIRE_THROWS_WITH(exec.run({{"x", HostTensor({4, 25})}}), Catch::Contains("expected [4, 24]"));
}

TEST_CASE("a weight missing from the file is named", "[graph]") {
    Graph g;
    g.output(ops::linear(g, g.input("x", {1, 3}), g.weight("nope.weight", {2, 3}), -1), "y");
    REQUIRE_THROWS_WITH(GpuExecutor(test::gpu(), g, WeightStore{}), Catch::Contains("'nope.weight' is missing"));
}

// run_cpu_values runs only what the wanted values depend on: the benches read a
// graph's ball indices through it without the MLPs' inputs or weights.
TEST_CASE("run_cpu_values computes only what the wanted values need", "[graph]") {
    const WeightStore full = WeightStore::load(write_mlp_file("mlp-values.safetensors"));
    Graph g = mlp_graph(5);
    const int z = g.input("z", {5, 3});  // read by no node that "hidden" needs
    g.output(ops::activation(g, ops::kActRelu, z, 0.01, "relu_z"), "z_relu");
    auto id_of = [&](const std::string& name) {
        for (auto& [n, id] : g.outputs())
            if (n == name) return id;
        for (size_t i = 0; i < g.values().size(); ++i)
            if (g.values()[i].kind == ValueKind::Input && g.values()[i].name == name) return int(i);
        FAIL("no value " << name);
        return -1;
    };
    const int hidden = id_of("hidden"), y = id_of("y"), x = id_of("x");
    const TensorMap in{{"x", random_tensor({5, 24}, 3)}, {"z", random_tensor({5, 3}, 4)}};
    const TensorMap want = run_cpu(g, full, in);

    // "hidden" needs fc0 and relu0 only: the later layers' weights and z may be absent.
    WeightStore first;
    first.add("mlp.0.weight", full.get("mlp.0.weight"));
    first.add("mlp.0.bias", full.get("mlp.0.bias"));
    const TensorMap only_x{{"x", in.at("x")}};
    const std::map<int, HostTensor> got = run_cpu_values(g, first, only_x, {hidden, x});
    REQUIRE(got.size() == 2);
    // The same CPU code on the same data: equal bit for bit.
    CHECK(got.at(hidden).data == want.at("hidden").data);
    CHECK(got.at(hidden).shape == want.at("hidden").shape);
    CHECK(got.at(x).data == in.at("x").data);  // an input is returned as given

    // All of them at once equals run_cpu.
    const std::map<int, HostTensor> all = run_cpu_values(g, full, in, {y, hidden});
    CHECK(all.at(y).data == want.at("y").data);

    REQUIRE_THROWS_WITH(run_cpu_values(g, first, only_x, {y}), Catch::Contains("'mlp.2.weight'"));
    REQUIRE_THROWS_WITH(run_cpu_values(g, full, only_x, {id_of("z_relu")}),
                        Catch::Contains("node 'relu_z' needs input 'z', not given"));
    REQUIRE_THROWS_WITH(run_cpu_values(g, full, {{"x", HostTensor({5, 23})}}, {hidden}),
                        Catch::Contains("shape [5, 23], expected [5, 24]"));
    REQUIRE_THROWS_WITH(run_cpu_values(g, full, {}, {z}), Catch::Contains("input 'z' is not given"));
    REQUIRE_THROWS_WITH(run_cpu_values(g, full, in, {int(g.values().size())}), Catch::Contains("is not in this graph"));
    REQUIRE_THROWS_WITH(run_cpu_values(g, full, in, {-1}), Catch::Contains("is not in this graph"));
}
