// topk and heatmap: GPU against the CPU references at odd sizes with fixed seeds,
// ties, the hand cases of weights_tools/tests/test_post.py, and bad inputs.
// Indices must match exactly; scores are computed with the same fp32 roundings
// on both sides, so they match exactly too. Heat-map tolerance: the default
// 1e-4 + 1e-4*|ref| (fp32 sqrt/exp against double; measured ~1e-6).
#include <catch2/catch.hpp>
#include <cmath>

#include "base/error.h"
#include "engine/model/post.h"
#include "engine/ops/build.h"
#include "tests/run_both.h"

using namespace vtloc;
using vtloc::test::random_tensor;

namespace {

// Candidates on a coarse grid so that many scores tie exactly.
HostTensor grid_candidates(int64_t M, uint32_t seed) {
    HostTensor t = random_tensor({M, 3}, seed, -4.0f, 4.0f);
    for (float& v : t.data) v = std::round(v) / 4.0f;
    return t;
}

// subgroup: the register shader where it applies (K <= 16, shuffles), or the sort.
test::BothRuns run_topk(const HostTensor& contact, const HostTensor& cand, int k, bool subgroup = true) {
    Graph g;
    std::vector<int> o = ops::topk(g, g.input("c", contact.shape), g.input("cand", cand.shape), k, "", subgroup);
    g.output(o[0], "index");
    g.output(o[1], "score");
    test::BothRuns r = test::run_both(g, WeightStore{}, {{"c", contact}, {"cand", cand}});
    test::require_same_ints(r.gpu.at("index"), r.cpu.at("index"), "topk.index, K = " + std::to_string(k));
    CHECK(r.gpu.at("score").data == r.cpu.at("score").data);
    return r;
}

}  // namespace

TEST_CASE("topk matches the CPU reference at odd sizes, with ties", "[op][topk]") {
    HostTensor c({3}, {0.1f, -0.2f, 0.05f});
    // K 1, 5, 16 take the register shader where the device has shuffles; K 64
    // and 256, and every K with subgroup off, the shared-memory sort.
    for (bool subgroup : {true, false})
        for (int64_t M : {1, 5, 37, 2049, 100003})
            for (int k : {1, 5, 16, 64}) {
                if (k > M) continue;
                INFO("M " << M << " K " << k << (subgroup ? "" : ", sort forced"));
                run_topk(c, random_tensor({M, 3}, uint32_t(M), -1.0f, 1.0f), k, subgroup);
                run_topk(HostTensor({1, 3}, {0, 0, 0}), grid_candidates(M, uint32_t(M) + 1), k, subgroup);  // many exact ties
            }
    run_topk(c, random_tensor({5000, 3}, 3, -1.0f, 1.0f), 256);  // the largest K
}

TEST_CASE("topk breaks ties to the lower index (test_post.py hand case)", "[op][topk]") {
    HostTensor cand({6, 3}, {1, 0, 0, 0, 1, 0, .5f, 0, 0, 0, 0, 1, 0, -1, 0, 0, 0, .5f});
    test::BothRuns r = run_topk(HostTensor({3}, {0, 0, 0}), cand, 4);
    CHECK(r.gpu.at("index").ints() == std::vector<int32_t>{2, 5, 0, 1});
    CHECK(r.gpu.at("score").data == std::vector<float>{0.25f, 0.25f, 1, 1});
    // All candidates identical: indices in order, by either shader.
    HostTensor same({300, 3});
    for (bool subgroup : {true, false}) {
        r = run_topk(HostTensor({3}, {1, 2, 3}), same, 7, subgroup);
        CHECK(r.gpu.at("index").ints() == std::vector<int32_t>{0, 1, 2, 3, 4, 5, 6});
    }
}

TEST_CASE("topk rejects K out of range, empty sets and NaN", "[op][topk]") {
    Graph g;
    int c = g.input("c", {3}), cand = g.input("cand", {4, 3}), empty = g.input("e", {0, 3}), bad = g.input("b", {4, 2});
    REQUIRE_THROWS_WITH(ops::topk(g, c, cand, 5), Catch::Contains("K = 5 exceeds the 4 candidates"));
    // Raw Params on purpose: a bad or missing K must be refused at Graph::add.
    REQUIRE_THROWS_WITH(g.add("topk", {c, cand}, {{"k", 0}}), Catch::Contains("K must be"));
    REQUIRE_THROWS_WITH(g.add("topk", {c, cand}), Catch::Contains("K must be"));
    REQUIRE_THROWS_WITH(ops::topk(g, c, empty, 1), Catch::Contains("empty"));
    REQUIRE_THROWS_WITH(ops::topk(g, c, bad, 1), Catch::Contains("[M, 3]"));
    Graph g2;
    g2.output(ops::topk(g2, g2.input("c", {3}), g2.input("cand", {2, 3}), 1)[0], "i");
    REQUIRE_THROWS_WITH(run_cpu(g2, WeightStore{}, {{"c", HostTensor({3}, {0, 0, 0})},
                                                    {"cand", HostTensor({2, 3}, {0, 0, 0, NAN, 0, 0})}}),
                        Catch::Contains("candidate 1 holds NaN"));
}

namespace {

// subgroup: the one-dispatch shader where the device has shuffles, or the two passes.
HostTensor run_heatmap(const HostTensor& cloud, const HostTensor& cand, const std::vector<int32_t>& index,
                       const HostTensor* sym = nullptr, bool subgroup = true) {
    Graph g;
    const int pc = g.input("cloud", cloud.shape), cd = g.input("cand", cand.shape);
    const int idx = g.input("index", {int64_t(index.size())}, ElemType::I32);
    TensorMap inputs{{"cloud", cloud}, {"cand", cand}, {"index", HostTensor::from_ints({int64_t(index.size())}, index)}};
    int symmetry = -1;
    if (sym) {
        symmetry = g.input("sym", sym->shape);
        inputs["sym"] = *sym;
    }
    g.output(ops::heatmap(g, pc, cd, idx, symmetry, "", subgroup), "heat");
    INFO("heat-map of " << cloud.shape[0] << " points" << (subgroup ? "" : ", two passes forced"));
    return test::run_gpu_and_compare(g, WeightStore{}, inputs).at("heat");
}

void check_close(const HostTensor& got, const std::vector<double>& want, double tol) {
    REQUIRE(got.data.size() == want.size());
    for (size_t i = 0; i < want.size(); ++i) {
        INFO("point " << i);
        CHECK(std::abs(got.data[i] - want[i]) <= tol);
    }
}

std::vector<double> minmax(std::vector<double> s) {
    double lo = *std::min_element(s.begin(), s.end()), hi = *std::max_element(s.begin(), s.end());
    for (double& v : s) v = (v - lo) / (hi - lo);
    return s;
}

}  // namespace

TEST_CASE("heatmap matches the CPU reference at odd sizes, with and without symmetry", "[op][heatmap]") {
    HostTensor cand = random_tensor({301, 3}, 1);
    std::vector<int32_t> idx{17, 3, 300, 0, 17};  // a repeated centre: its lower rank wins
    HostTensor sym = symmetry_transforms({0.1, -0.2, 0.0}, {0.3, 1.0, -0.2}, 5);
    for (bool subgroup : {true, false}) {
        run_heatmap(random_tensor({1037, 6}, 2), cand, idx, nullptr, subgroup);
        run_heatmap(random_tensor({1, 3}, 3), cand, {5}, nullptr, subgroup);
        run_heatmap(random_tensor({513, 3}, 4), cand, idx, &sym, subgroup);
        run_heatmap(random_tensor({100000, 3}, 5), random_tensor({7, 3}, 6), {6, 5, 4, 3, 2, 1, 0}, nullptr, subgroup);
    }
}

TEST_CASE("heatmap hand cases of test_post.py: ties, flat, symmetry order 2", "[op][heatmap]") {
    // centres (0,0,0) rank 1, (1,0,0) rank 2; p2 is equidistant: rank 1 wins.
    HostTensor cand({2, 3}, {0, 0, 0, 1, 0, 0});
    HostTensor pts({4, 3}, {0, 0, 0, 1, 0, 0, .5f, 0, 0, 3, 0, 0});
    HostTensor h = run_heatmap(pts, cand, {0, 1});
    check_close(h, minmax({1.0, 0.5, std::exp(-0.5), std::exp(-2.0) / 2}), 1e-6);
    CHECK(h.data[0] == 1.0f);
    CHECK(h.data[3] == 0.0f);
    // flat: every point at distance 1 of the only centre
    HostTensor flat = run_heatmap(HostTensor({3, 3}, {1, 0, 0, 0, 1, 0, 0, 0, -1}), HostTensor({1, 3}), {0});
    CHECK(flat.data == std::vector<float>{0, 0, 0});
    // order-2 symmetry about z: copies (-.5, 0, .2) rank 1 and (0, -.5, 0) rank 2
    HostTensor c2({2, 3}, {.5f, 0, .2f, 0, .5f, 0});
    HostTensor p2({4, 3}, {.5f, 0, .2f, -.5f, 0, .2f, 0, -.5f, 0, 0, 0, .2f});
    HostTensor sym = symmetry_transforms({0, 0, 0}, {0, 0, 1}, 2);
    check_close(run_heatmap(p2, c2, {0, 1}, &sym), {1.0, 1.0, 0.0, (std::exp(-0.5) - 0.5) / 0.5}, 1e-6);
    CHECK(run_heatmap(p2, c2, {0, 1}).data[1] < 0.5f);  // without the prior p1 takes the rank-2 centre
}

TEST_CASE("symmetry transforms rotate about the axis line", "[op][heatmap]") {
    // 90 degrees about the z line through (1, 1, 0): (2, 1, 0) -> (1, 2, 0)
    HostTensor t = symmetry_transforms({1, 1, 0}, {0, 0, 2}, 4);
    const float* a = &t.data[12];
    double p[3] = {2, 1, 0}, q[3];
    for (int r = 0; r < 3; ++r) q[r] = a[4 * r] * p[0] + a[4 * r + 1] * p[1] + a[4 * r + 2] * p[2] + a[4 * r + 3];
    CHECK(std::abs(q[0] - 1) < 1e-6);
    CHECK(std::abs(q[1] - 2) < 1e-6);
    CHECK(std::abs(q[2]) < 1e-6);
    REQUIRE_THROWS_WITH(symmetry_transforms({0, 0, 0}, {0, 0, 0}, 2), Catch::Contains("non-zero"));
    REQUIRE_THROWS_WITH(symmetry_transforms({0, 0, 0}, {0, 0, 1}, 0), Catch::Contains(">= 1"));
}

TEST_CASE("require_finite names the tensor and the element", "[op][topk]") {
    HostTensor t({2, 3}, {0, 1, 2, 3, NAN, 5});
    REQUIRE_THROWS_WITH(require_finite(t, "candidates"), Catch::Contains("candidates holds NaN at element 4"));
    t.data[4] = INFINITY;
    REQUIRE_THROWS_WITH(require_finite(t, "cloud"), Catch::Contains("cloud holds inf"));
    t.data[4] = 4;
    CHECK_NOTHROW(require_finite(t, "cloud"));
}

TEST_CASE("heatmap rejects bad inputs", "[op][heatmap]") {
    Graph g;
    int cloud = g.input("cloud", {5, 2}), c3 = g.input("c3", {5, 3}), idx = g.input("i", {2}, ElemType::I32);
    int fidx = g.input("f", {2}), sym = g.input("s", {2, 9});
    REQUIRE_THROWS_WITH(ops::heatmap(g, cloud, c3, idx, -1), Catch::Contains("[P, D >= 3]"));
    REQUIRE_THROWS_WITH(ops::heatmap(g, c3, c3, fidx, -1), Catch::Contains("must be I32"));
    REQUIRE_THROWS_WITH(ops::heatmap(g, c3, c3, idx, sym), Catch::Contains("[T > 0, 12]"));
    Graph g2;
    g2.output(ops::heatmap(g2, g2.input("p", {2, 3}), g2.input("c", {2, 3}), g2.input("i", {1}, ElemType::I32), -1), "h");
    REQUIRE_THROWS_WITH(run_cpu(g2, WeightStore{}, {{"p", HostTensor({2, 3})}, {"c", HostTensor({2, 3})},
                                                    {"i", HostTensor::from_ints({1}, {2})}}),
                        Catch::Contains("index 2 is outside 0..1"));
}

TEST_CASE("topk and heatmap run a batch of contacts, each row as if alone", "[op][topk][heatmap]") {
    // Batches of 3 and 7 contacts: one pass (M = 37), several passes (2049 with
    // K = 64, 100003 with K = 5). GPU against CPU exactly, and every row of the
    // batch exactly as the unbatched op gives it on the GPU.
    for (int64_t M : {37, 2049, 100003})
        for (int64_t B : {3, 7}) {
            const int k = M == 2049 ? 64 : 5;
            INFO("M " << M << " B " << B << " K " << k);
            HostTensor contacts = random_tensor({B, 3}, uint32_t(M + B), -1.0f, 1.0f);
            HostTensor cand = grid_candidates(M, uint32_t(M) + 7);  // ties across rows too
            HostTensor cloud = random_tensor({513, 6}, uint32_t(B));
            Graph g;
            const int c = g.input("c", contacts.shape), cd = g.input("cand", cand.shape), pc = g.input("cloud", cloud.shape);
            std::vector<int> top = ops::topk(g, c, cd, k);
            g.output(top[0], "index");
            g.output(top[1], "score");
            g.output(ops::heatmap(g, pc, cd, top[0], -1), "heat");
            test::BothRuns r = test::run_both(g, WeightStore{}, {{"c", contacts}, {"cand", cand}, {"cloud", cloud}});
            REQUIRE(r.gpu.at("index").shape == Shape{B, k});
            REQUIRE(r.gpu.at("heat").shape == Shape{B, 513});
            test::require_same_ints(r.gpu.at("index"), r.cpu.at("index"), "batched topk.index");
            CHECK(r.gpu.at("score").data == r.cpu.at("score").data);
            test::require_close(r.gpu.at("heat"), r.cpu.at("heat"), test::Tolerance{}, "batched heat-map");
            for (int64_t b = 0; b < B; ++b) {
                HostTensor one({3}, {contacts.data[size_t(3 * b)], contacts.data[size_t(3 * b + 1)], contacts.data[size_t(3 * b + 2)]});
                Graph g1;
                const int c1 = g1.input("c", {3}), cd1 = g1.input("cand", cand.shape), pc1 = g1.input("cloud", cloud.shape);
                std::vector<int> t1 = ops::topk(g1, c1, cd1, k);
                g1.output(t1[0], "index");
                g1.output(ops::heatmap(g1, pc1, cd1, t1[0], -1), "heat");
                GpuExecutor exec(test::gpu(), g1, WeightStore{});
                TensorMap single = exec.run({{"c", one}, {"cand", cand}, {"cloud", cloud}});
                std::vector<int32_t> all = r.gpu.at("index").ints();
                CHECK(std::vector<int32_t>(all.begin() + b * k, all.begin() + (b + 1) * k) == single.at("index").ints());
                const auto& heat = r.gpu.at("heat").data;
                CHECK(std::vector<float>(heat.begin() + b * 513, heat.begin() + (b + 1) * 513) == single.at("heat").data);
            }
        }
}
