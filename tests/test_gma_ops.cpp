// GMA ops (disentangle, gma_decode) and chamfer: GPU against the CPU references
// at odd sizes, fixed seeds; the weight row-chunk planner with forced small limits.
// Tolerance: the default 1e-4 + 1e-4*|ref| (the CPU sums in double, the shaders
// in fp32; measured max errors are ~1e-6 relative, see the report).
#include <catch2/catch.hpp>

#include "base/error.h"
#include "engine/model/gma.h"
#include "engine/ops/build.h"
#include "engine/ops/common.h"
#include "tests/harness.h"

using namespace vtloc;
using vtloc::test::random_tensor;
using vtloc::test::run_gpu_and_compare;

namespace {

// x [rows, K] times W [K, J, L] split into chunks of `chunk_rows` rows.
// shuffles: the subgroup variant (the default where the device has shuffles) or
// the shared-memory slabs.
void check_disentangle(int64_t rows, int64_t K, int64_t J, int64_t L, int64_t chunk_rows, uint32_t seed,
                       bool shuffles) {
    WeightStore w;
    w.add("wd", random_tensor({K, J, L}, seed + 1, -0.3f, 0.3f));
    std::vector<std::string> names = split_weight_rows(w, "wd", uint64_t(chunk_rows * J * L * 4));
    CHECK(names.size() == size_t((K + chunk_rows - 1) / chunk_rows));
    Graph g;
    std::vector<int> in{g.input("x", {rows, K})};
    for (const std::string& n : names) in.push_back(g.weight(n, w.get(n).shape));
    g.output(ops::disentangle(g, in, ops::kActLeaky, 0.01, "", shuffles), "y");
    REQUIRE(g.value(g.outputs()[0].second).shape == Shape{rows, J, L});
    INFO("disentangle " << rows << "x" << K << " by [" << K << ", " << J << ", " << L << "] in " << names.size()
                        << " chunks, " << (shuffles ? "shuffles where the device has them" : "shared-memory slabs"));
    run_gpu_and_compare(g, w, {{"x", random_tensor({rows, K}, seed, -2.0f, 2.0f)}});
}

}  // namespace

TEST_CASE("row-chunk planner keeps every chunk within the limit", "[op][disentangle]") {
    CHECK(plan_row_chunks(256, 262144, 1ull << 27) == std::vector<int64_t>{256});  // paper W^d, lavapipe
    CHECK(plan_row_chunks(256, 262144, 100 * 262144) == std::vector<int64_t>{100, 100, 56});
    CHECK(plan_row_chunks(7, 10, 10) == std::vector<int64_t>(7, 1));
    CHECK(plan_row_chunks(0, 10, 100).empty());
    REQUIRE_THROWS_WITH(plan_row_chunks(3, 101, 100), Catch::Contains("exceeds the binding limit"));
    WeightStore w;
    w.add("t", random_tensor({10, 3}, 1));
    CHECK(split_weight_rows(w, "t", 1000) == std::vector<std::string>{"t"});  // fits: not copied
    auto names = split_weight_rows(w, "t", 4 * 3 * 4);
    REQUIRE(names == std::vector<std::string>{"t#0", "t#1", "t#2"});
    CHECK(w.get("t#2").shape == Shape{2, 3});
    CHECK(w.get("t#2").data[5] == w.get("t").data[29]);
    CHECK(weight_row_chunks(w, "t") == names);
    REQUIRE_THROWS_WITH(split_weight_rows(w, "t", 8 * 3 * 4), Catch::Contains("already split"));
}

TEST_CASE("disentangle matches the CPU reference, whole and split", "[op][disentangle]") {
    for (bool s : {true, false}) {
        check_disentangle(1, 37, 13, 7, 37, 1, s);     // one chunk
        check_disentangle(1, 37, 13, 7, 10, 2, s);     // 10 + 10 + 10 + 7 rows
        check_disentangle(3, 64, 129, 5, 1, 3, s);     // one row per chunk, several input rows
        check_disentangle(1, 256, 300, 64, 97, 4, s);  // long rows, ragged column blocks
        check_disentangle(19, 70, 9, 12, 25, 5, s);    // a batch: row blocks of 8, 8 and 3, three chunks
        check_disentangle(8, 33, 7, 3, 33, 6, s);      // exactly one row block, V = 1
    }
}

TEST_CASE("disentangle rejects mismatched chunks", "[op][disentangle]") {
    Graph g;
    int x = g.input("x", {1, 10});
    int a = g.weight("a", {6, 4, 2}), b = g.weight("b", {3, 4, 2}), c = g.weight("c", {4, 4, 3});
    REQUIRE_THROWS_WITH(ops::disentangle(g, {x, a, b}, ops::kActNone, 0.01), Catch::Contains("hold 9 rows"));
    REQUIRE_THROWS_WITH(ops::disentangle(g, {x, a, c}, ops::kActNone, 0.01), Catch::Contains("differ after the first axis"));
}

TEST_CASE("gma_decode matches the CPU reference", "[op][gma_decode]") {
    HostTensor o = random_tensor({1, 37, 6}, 7, -3.0f, 3.0f);
    for (int c = 3; c < 6; ++c) o.data[size_t(6 * 5 + c)] = 0.0f;  // a zero normal stays zero
    for (int c = 3; c < 6; ++c) o.data[size_t(6 * 6 + c)] = c == 3 ? 1e-8f : 0.0f;  // below the 1e-6 clamp
    Graph g;
    g.output(ops::gma_decode(g, g.input("o", o.shape)), "y");
    TensorMap out = run_gpu_and_compare(g, WeightStore{}, {{"o", o}});
    const float* r = &out.at("y").data[6 * 9];
    CHECK(std::abs(r[3] * r[3] + r[4] * r[4] + r[5] * r[5] - 1.0f) < 1e-5f);
    CHECK(out.at("y").data[6 * 5 + 4] == 0.0f);
    CHECK(std::abs(out.at("y").data[6 * 6 + 3] - 0.01f) < 1e-6f);
}

namespace {

// shuffles: the search by subgroup shuffles (the default where the device has
// them) or, false, the shared-memory tiled one.
// queries: per thread of the shuffle search (0: the device's choice, 4 on lavapipe).
TensorMap check_chamfer(const Shape& a, const Shape& b, uint32_t seed, bool shuffles = true, int queries = 0) {
    Graph g;
    std::vector<int> out = ops::chamfer(g, g.input("a", a), g.input("b", b), "", shuffles, queries);
    g.output(out[0], "chamfer");
    g.output(out[1], "mins");
    INFO("chamfer " << shape_str(a) << " vs " << shape_str(b) << (shuffles ? ", shuffles where the device has them" : ", shared-memory tiles")
                    << ", queries per thread " << queries);
    return run_gpu_and_compare(g, WeightStore{},
                               {{"a", random_tensor(a, seed, -1.0f, 1.0f)}, {"b", random_tensor(b, seed + 1, -1.0f, 1.0f)}});
}

}  // namespace

TEST_CASE("chamfer matches the CPU reference at odd sizes, widths 3 and 6", "[op][chamfer]") {
    for (bool shuffles : {true, false}) {
        check_chamfer({37, 3}, {53, 3}, 1, shuffles);
        check_chamfer({1, 6}, {1, 6}, 2, shuffles);
        check_chamfer({1, 300, 6}, {257, 6}, 3, shuffles);  // leading axes are flattened into rows
        check_chamfer({1000, 3}, {7, 3}, 4, shuffles);
        // Over 65,535 targets a query's scan is split across dispatches: lavapipe
        // silently ends a longer loop, and one scan of these 70,000 gave wrong minima.
        check_chamfer({5, 3}, {70000, 3}, 8, shuffles);
    }
}

TEST_CASE("chamfer gives the same distances at every number of queries per thread", "[op][chamfer]") {
    // Each query sees the same targets in the same order at any Q, so its minimum
    // (and NaN flag) is the same float: bit-identical to Q = 1 (the GPU default),
    // and each also against the CPU reference. Odd sizes leave partial last
    // workgroups and partial rounds of targets; 70,000 targets cross the chunks.
    const std::vector<std::pair<Shape, Shape>> sizes{
        {{37, 3}, {53, 3}}, {{1, 300, 6}, {257, 6}}, {{3, 130, 6}, {61, 6}}, {{1000, 3}, {7, 3}}, {{5, 3}, {70000, 3}}};
    uint32_t seed = 40;
    for (const auto& [a, b] : sizes) {
        TensorMap one = check_chamfer(a, b, seed, true, 1);
        for (int q : {2, 3, 4, 7, 8}) {
            TensorMap many = check_chamfer(a, b, seed, true, q);
            CHECK(many.at("chamfer").data == one.at("chamfer").data);
            CHECK(many.at("mins").data == one.at("mins").data);
        }
        ++seed;
    }
    Graph g;
    int a = g.input("a", {4, 3});
    REQUIRE_THROWS_WITH(ops::chamfer(g, a, a, "", true, 9), Catch::Contains("queries per thread must be 0"));
    REQUIRE_THROWS_WITH(ops::chamfer(g, a, a, "", true, -1), Catch::Contains("queries per thread must be 0"));
}

TEST_CASE("chamfer of a hand case and of identical sets", "[op][chamfer]") {
    // a = {0}, b = {1, 2} on the x axis: 1 + (1 + 4) / 2
    Graph g;
    g.output(ops::chamfer(g, g.input("a", {1, 3}), g.input("b", {2, 3}))[0], "d");
    GpuExecutor exec(test::gpu(), g, WeightStore{});
    TensorMap out = exec.run({{"a", HostTensor({1, 3}, {0, 0, 0})}, {"b", HostTensor({2, 3}, {1, 0, 0, 2, 0, 0})}});
    test::require_no_validation_messages();
    CHECK(out.at("d").shape == Shape{});
    CHECK(out.at("d").data[0] == 3.5f);
    HostTensor same = random_tensor({77, 6}, 9);
    Graph g2;
    g2.output(ops::chamfer(g2, g2.input("a", {77, 6}), g2.input("b", {77, 6}))[0], "d");
    CHECK(GpuExecutor(test::gpu(), g2, WeightStore{}).run({{"a", same}, {"b", same}}).at("d").data[0] == 0.0f);
    test::require_no_validation_messages();
}

TEST_CASE("chamfer compares a batch of sets with one cloud, each as if alone", "[op][chamfer]") {
    // A [S, Na, D] with S > 1: S distances, GPU against CPU, and each set's value
    // and nearest distances bit-identical to the unbatched op's on the GPU.
    for (auto [S, shuffles] : {std::pair<int64_t, bool>{2, true}, {5, true}, {3, false}}) {
        const Shape a{S, 300, 6}, b{257, 6};
        TensorMap out = check_chamfer(a, b, uint32_t(20 + S), shuffles);
        REQUIRE(out.at("chamfer").shape == Shape{S});
        HostTensor all = random_tensor(a, uint32_t(20 + S), -1.0f, 1.0f), cloud = random_tensor(b, uint32_t(21 + S), -1.0f, 1.0f);
        Graph g;
        std::vector<int> one = ops::chamfer(g, g.input("a", {300, 6}), g.input("b", b), "", shuffles);
        g.output(one[0], "chamfer");
        g.output(one[1], "mins");
        GpuExecutor exec(test::gpu(), g, WeightStore{});
        for (int64_t s = 0; s < S; ++s) {
            HostTensor set({300, 6}, std::vector<float>(all.data.begin() + s * 1800, all.data.begin() + (s + 1) * 1800));
            TensorMap single = exec.run({{"a", set}, {"b", cloud}});
            CHECK(out.at("chamfer").data[size_t(s)] == single.at("chamfer").data[0]);
            const auto& mins = out.at("mins").data;
            CHECK(std::vector<float>(mins.begin() + s * 557, mins.begin() + (s + 1) * 557) == single.at("mins").data);
        }
        test::require_no_validation_messages();
    }
}

TEST_CASE("chamfer at 16384 x 16384", "[long][chamfer]") {
    // The long suite's: 4 s a run here (GPU and CPU oracle), at subgroups 8 and 4. Its
    // paths run in the command at odd sizes: width 6, many workgroups, a sum over
    // 70,005 minima and the scan split across dispatches.
    check_chamfer({16384, 6}, {16384, 6}, 11);
}

TEST_CASE("chamfer rejects empty sets, bad and mismatched widths, NaN", "[op][chamfer]") {
    Graph g;
    int a3 = g.input("a3", {5, 3}), b6 = g.input("b6", {4, 6}), e = g.input("e", {0, 3}), w4 = g.input("w4", {2, 4});
    REQUIRE_THROWS_WITH(ops::chamfer(g, a3, b6), Catch::Contains("different widths"));
    REQUIRE_THROWS_WITH(ops::chamfer(g, a3, e), Catch::Contains("B is empty"));
    REQUIRE_THROWS_WITH(ops::chamfer(g, w4, w4), Catch::Contains("width 3 or 6"));
    Graph g2;
    g2.output(ops::chamfer(g2, g2.input("a", {2, 3}), g2.input("b", {2, 3}))[0], "d");
    HostTensor bad({2, 3}, {0, 0, 0, 1, std::nanf(""), 0});
    REQUIRE_THROWS_WITH(run_cpu(g2, WeightStore{}, {{"a", bad}, {"b", bad}}), Catch::Contains("NaN"));
    // The GPU cannot throw: it reports NaN instead of a number that looks valid.
    float d = GpuExecutor(test::gpu(), g2, WeightStore{}).run({{"a", bad}, {"b", bad}}).at("d").data[0];
    test::require_no_validation_messages();
    CHECK(std::isnan(d));
    // A NaN in one query marks that query's minimum only, also where a thread
    // holds several queries (rows 6, 70, 134 share a thread at 64 x 4): every B
    // row sees it as a target.
    for (int q : {1, 4}) {
        Graph g3;
        std::vector<int> out = ops::chamfer(g3, g3.input("a", {200, 3}), g3.input("b", {9, 3}), "", true, q);
        g3.output(out[1], "mins");
        HostTensor a = test::random_tensor({200, 3}, 5), b = test::random_tensor({9, 3}, 6);
        a.data[70 * 3 + 1] = std::nanf("");
        std::vector<float> mins = GpuExecutor(test::gpu(), g3, WeightStore{}).run({{"a", a}, {"b", b}}).at("mins").data;
        test::require_no_validation_messages();
        INFO("queries per thread " << q);
        for (int i = 0; i < 209; ++i) CHECK(std::isnan(mins[size_t(i)]) == (i == 70 || i >= 200));
    }
}
