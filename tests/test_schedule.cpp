// The executor's node orders (engine/executor.h Schedule): the steps of
// Graph::stepped_order, their memory plan and scratch, and the same bits as one
// node at a time (the tiny model's: tests/test_vtloc_model.cpp).
#include <catch2/catch.hpp>

#include <algorithm>
#include <climits>
#include <initializer_list>
#include <map>
#include <utility>

#include "engine/ops/build.h"
#include "tests/harness.h"

using namespace vtloc;
using vtloc::test::random_tensor;

namespace {

// Two branches from one input, of 4 and 2 nodes, each with a convolution split
// in parts (scratch) at the same depth; joined by an add, then one more node.
// Node indices interleave the branches' construction unevenly on purpose.
Graph two_branch_graph(WeightStore& w) {
    Graph g;
    const int x = g.input("x", {1, 6, 9, 11});
    ops::Conv2d c;
    c.pad_h = c.pad_w = 1;
    c.split = 2;
    auto weight = [&](const std::string& name, Shape s, uint32_t seed) {
        w.add(name, random_tensor(s, seed, -0.3f, 0.3f));
        return g.weight(name, s);
    };
    int a = ops::conv2d(g, x, weight("a0.w", {6, 6, 3, 3}, 1), weight("a0.b", {6}, 2), -1, c, "a0");
    int b = ops::conv2d(g, x, weight("b0.w", {6, 6, 3, 3}, 3), weight("b0.b", {6}, 4), -1, c, "b0");
    a = ops::activation(g, ops::kActRelu, a, 0.01, "a1");
    a = ops::activation(g, ops::kActTanh, a, 0.01, "a2");
    b = ops::activation(g, ops::kActSigmoid, b, 0.01, "b1");
    a = ops::activation(g, ops::kActLeaky, a, 0.01, "a3");
    const int s = ops::binary(g, ops::Binary::Add, a, b, "join");
    g.output(ops::activation(g, ops::kActRelu, s, 0.01, "out"), "y");
    g.output(b, "b");
    return g;
}

// What every stepped order must hold: a permutation, steps from 0 without gaps,
// producers in earlier steps, as many steps as the longest chain of nodes.
void check_steps(const Graph& g, const std::vector<int>& order, const std::vector<int>& step) {
    REQUIRE(order.size() == g.nodes().size());
    REQUIRE(step.size() == order.size());
    std::vector<int> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    for (size_t i = 0; i < sorted.size(); ++i) REQUIRE(sorted[i] == int(i));
    CHECK(step.front() == 0);
    for (size_t i = 1; i < step.size(); ++i) CHECK((step[i] == step[i - 1] || step[i] == step[i - 1] + 1));
    const std::vector<int> producer = g.producers();
    std::vector<int> step_of(g.nodes().size()), depth(g.nodes().size(), 0);
    for (size_t i = 0; i < order.size(); ++i) step_of[size_t(order[i])] = step[i];
    int longest = 0;
    for (int n : g.topo_order()) {
        for (int in : g.nodes()[size_t(n)].inputs)
            if (int p = producer[size_t(in)]; p >= 0) {
                CHECK(step_of[size_t(p)] < step_of[size_t(n)]);
                depth[size_t(n)] = std::max(depth[size_t(n)], depth[size_t(p)] + 1);
            }
        longest = std::max(longest, depth[size_t(n)]);
    }
    CHECK(step.back() == longest);
}

}  // namespace

TEST_CASE("stepped orders keep producers in earlier steps and independent branches together", "[graph]") {
    WeightStore w;
    const Graph g = two_branch_graph(w);
    auto id = [&](const std::string& name) {
        for (size_t i = 0; i < g.nodes().size(); ++i)
            if (g.nodes()[i].name == name) return int(i);
        FAIL("no node " << name);
        return -1;
    };
    std::vector<int> early_step, late_step;
    const std::vector<int> early = g.stepped_order(&early_step), late = g.stepped_order(&late_step, true);
    check_steps(g, early, early_step);
    check_steps(g, late, late_step);
    auto step_in = [&](const std::vector<int>& order, const std::vector<int>& step, const std::string& name) {
        return step[size_t(std::find(order.begin(), order.end(), id(name)) - order.begin())];
    };
    // Early: both convolutions first, the short branch's second node beside a1.
    CHECK(step_in(early, early_step, "a0") == 0);
    CHECK(step_in(early, early_step, "b0") == 0);
    CHECK(step_in(early, early_step, "b1") == 1);
    // Late: the short branch as close to the join as it can be.
    CHECK(step_in(late, late_step, "b0") == 2);
    CHECK(step_in(late, late_step, "b1") == 3);
    CHECK(step_in(late, late_step, "join") == 4);
}

TEST_CASE("a stepped memory plan never overlaps values alive in one step", "[graph]") {
    WeightStore w;
    const Graph g = two_branch_graph(w);
    for (bool late : {false, true}) {
        INFO((late ? "late" : "early"));
        std::vector<int> step;
        const std::vector<int> order = g.stepped_order(&step, late);
        const MemoryPlan plan = plan_memory(g, order, 64, true, step);
        const auto& vals = g.values();
        std::vector<int> first(vals.size(), INT_MAX), last(vals.size(), -2);
        for (size_t i = 0; i < vals.size(); ++i)
            if (vals[i].kind == ValueKind::Input) first[i] = last[i] = -1;
        for (size_t pos = 0; pos < order.size(); ++pos) {
            for (int o : g.nodes()[size_t(order[pos])].outputs) first[size_t(o)] = last[size_t(o)] = step[pos];
            for (int in : g.nodes()[size_t(order[pos])].inputs) last[size_t(in)] = std::max(last[size_t(in)], step[pos]);
        }
        for (auto& [n, v] : g.outputs()) last[size_t(v)] = INT_MAX;
        for (size_t a = 0; a < vals.size(); ++a)
            for (size_t b = a + 1; b < vals.size(); ++b) {
                if (plan.offset[a] < 0 || plan.offset[b] < 0) continue;
                const bool together = first[a] <= last[b] && first[b] <= last[a];
                const int64_t ea = plan.offset[a] + numel(vals[a].shape) * 4, eb = plan.offset[b] + numel(vals[b].shape) * 4;
                INFO(vals[a].name << " and " << vals[b].name);
                CHECK(!(together && plan.offset[a] < eb && plan.offset[b] < ea));
            }
    }
    // Steps that disagree with the order are refused by name.
    std::vector<int> step;
    const std::vector<int> order = g.stepped_order(&step);
    step.pop_back();
    REQUIRE_THROWS_WITH(plan_memory(g, order, 64, true, step), Catch::Contains("steps for"));
}

TEST_CASE("every schedule gives the same bits with fewer barriers in steps", "[graph]") {
    WeightStore w;
    const Graph g = two_branch_graph(w);
    const TensorMap in{{"x", random_tensor({1, 6, 9, 11}, 5, -1.f, 1.f)}};
    const TensorMap want = run_cpu(g, w, in);
    auto resident = std::make_shared<ResidentWeights>(test::gpu());
    GpuExecutor serial(test::gpu(), g, w, resident, false, false, Schedule::Serial);
    const TensorMap ref = serial.run(in);
    test::require_close(ref.at("y"), want.at("y"), {}, "y, serial");
    // The two split convolutions share a step: their scratch lies side by side.
    const uint64_t one = serial.memory_plan().scratch_bytes;
    REQUIRE(one > 0);
    std::map<Schedule, uint32_t> barriers;
    for (Schedule s : {Schedule::Steps, Schedule::Late}) {
        INFO(schedule_name(s));
        GpuExecutor ex(test::gpu(), g, w, resident, false, false, s);
        for (int rep = 0; rep < 2; ++rep) {  // resubmitted, the same
            const TensorMap got = ex.run(in);
            CHECK(got.at("y").data == ref.at("y").data);
            CHECK(got.at("b").data == ref.at("b").data);
        }
        CHECK(ex.sequence().barrier_count() < serial.sequence().barrier_count());
        CHECK(ex.memory_plan().scratch_bytes == (s == Schedule::Steps ? 2 * one : one));
        barriers[s] = ex.sequence().barrier_count();
    }
    // The same steps and split nodes, so the same barriers: the two convolutions of
    // the early order's first step would add one between them if their scratch overlapped.
    CHECK(barriers[Schedule::Steps] == barriers[Schedule::Late]);
    // Profiling times one node at a time, whatever the schedule asked.
    GpuExecutor profiled(test::gpu(), g, w, resident, true, false, Schedule::Steps);
    CHECK(profiled.sequence().barrier_count() == serial.sequence().barrier_count());
    test::require_no_validation_messages();
}

TEST_CASE("resident weights: a failed build's batch goes back unless another build reads it", "[graph]") {
    rt::Context& ctx = test::gpu();
    WeightStore w;
    w.add("a", random_tensor({1000}, 1, -1.f, 1.f));
    w.add("b", random_tensor({2000}, 2, -1.f, 1.f));
    w.add("c", random_tensor({3000}, 3, -1.f, 1.f));
    auto reading = [](std::initializer_list<std::pair<const char*, int64_t>> names) {
        Graph g;
        for (const auto& [name, n] : names) g.weight(name, {n});
        return g;
    };
    ResidentWeights r(ctx);
    const uint64_t start = ctx.memory_in_use();
    const size_t first = r.ensure(reading({{"a", 1000}}), w);
    CHECK(first != ResidentWeights::kNone);
    const uint64_t with_a = ctx.memory_in_use();
    CHECK(with_a > start);
    // A second graph reading "a" and "b": only "b" is uploaded, and "a"'s batch is now read by two.
    const size_t second = r.ensure(reading({{"a", 1000}, {"b", 2000}}), w);
    CHECK(second != first);
    CHECK(r.ensure(reading({{"b", 2000}}), w) == ResidentWeights::kNone);  // nothing new
    CHECK(r.count() == 2);
    r.forget(first);  // shared: stays
    CHECK(r.has("a"));
    CHECK(ctx.memory_in_use() > with_a);
    const uint64_t with_ab = ctx.memory_in_use();
    // A batch nobody else read goes back whole.
    const size_t third = r.ensure(reading({{"c", 3000}}), w);
    CHECK(ctx.memory_in_use() > with_ab);
    r.forget(third);
    CHECK(!r.has("c"));
    CHECK(ctx.memory_in_use() == with_ab);
    CHECK_THROWS_WITH(r.view("c"), Catch::Contains("'c' is not resident"));
    r.forget(third);  // twice, or a batch that never was: nothing
    r.forget(99);
    CHECK(r.has("a"));
    CHECK(r.has("b"));
    CHECK(r.view("a").size >= 4000);
    // Its shape is checked against the resident copy's.
    CHECK_THROWS_WITH(r.ensure(reading({{"a", 999}}), w), Catch::Contains("resident as"));
}
