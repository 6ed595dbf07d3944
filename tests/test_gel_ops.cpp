// The gel's shape ops (gel_gradient, masked_poisson) against their CPU references
// (engine/ops/gel_ops.h) at odd sizes with fixed seeds, and their shape errors.
#include <catch2/catch.hpp>
#include <cmath>

#include "engine/ops/build.h"
#include "engine/ops/gel_ops.h"
#include "tests/harness.h"

using namespace vtloc;

namespace {

HostTensor grey(int64_t H, int64_t W, uint32_t seed) {
    HostTensor t = test::random_tensor({H, W, 3}, seed, 0.0f, 255.0f);
    for (float& v : t.data) v = std::floor(v);
    return t;
}

}  // namespace

TEST_CASE("gel_gradient matches the CPU reference", "[op][gel][gel_gradient]") {
    struct Case {
        int64_t H, W, n, ty, tx;
    };
    for (const Case& k : {Case{1, 1, 2, 1, 1}, Case{7, 13, 8, 1, 1}, Case{13, 17, 8, 2, 5}, Case{120, 160, 64, 3, 4}}) {
        INFO(k.H << "x" << k.W << " n " << k.n << " tiles " << k.ty << "x" << k.tx);
        Graph g;
        const int out = ops::gel_gradient(g, g.input("frame", {k.H, k.W, 3}), g.input("empty", {k.H, k.W, 3}),
                                          g.input("tables", {k.ty * k.tx, k.n * k.n * k.n, 2}), k.n, k.ty, k.tx);
        g.output(out, "gradient");
        const uint32_t seed = uint32_t(k.H * 31 + k.n);
        TensorMap in{{"frame", grey(k.H, k.W, seed)}, {"empty", grey(k.H, k.W, seed + 1)},
                     {"tables", test::random_tensor({k.ty * k.tx, k.n * k.n * k.n, 2}, seed + 2, -3.0f, 3.0f)}};
        test::run_gpu_and_compare(g, WeightStore{}, in);
    }
}

TEST_CASE("gel_gradient: no colour change gives no gradient, and one cell gives its table value", "[op][gel][gel_gradient]") {
    const int n = 4;
    std::vector<float> lut(size_t(n * n * n * 2), 0.f);
    const float d[3] = {100, -3, 0};  // cells 2, 1, 2 of 4: (v + 256) / 128, floored
    const uint32_t cell = (2u * n + 1u) * n + 2u;
    lut[2 * cell] = 0.75f, lut[2 * cell + 1] = -0.5f;
    float gr = 0, gc = 0;
    ops::gel::table_gradient(lut.data(), n, 1, 1, 5, 5, 2, 2, d, gr, gc);
    CHECK(gr == 0.75f);
    CHECK(gc == -0.5f);
    const float frame[3] = {7, 7, 7};
    ops::gel::indentation_gradient(lut.data(), n, 1, 1, 1, 1, frame, frame, 0, 0, gr, gc);
    CHECK((gr == 0.0f && gc == 0.0f));
}

TEST_CASE("masked_poisson matches the CPU reference and solves a known cap", "[op][gel][masked_poisson]") {
    for (int64_t iterations : {0, 1, 7, 50}) {
        for (auto [H, W] : {std::pair<int64_t, int64_t>{1, 9}, {11, 7}, {40, 53}}) {
            INFO(H << "x" << W << ", " << iterations << " sweeps");
            Graph g;
            g.output(ops::masked_poisson(g, g.input("gradient", {H, W, 2}), g.input("mask", {H, W}), iterations, 1.85), "height");
            HostTensor mask({H, W});
            for (int64_t i = 0; i < H * W; ++i) mask.data[size_t(i)] = (i * 7 + 3) % 11 < 8;  // holes and islands
            TensorMap in{{"gradient", test::random_tensor({H, W, 2}, uint32_t(H * W + iterations), -1.0f, 1.0f)}, {"mask", mask}};
            test::run_gpu_and_compare(g, WeightStore{}, in);
        }
    }
    // A paraboloid cap z = 1 - rho^2 / 100 on the disc rho < 10 (zero on its rim): its gradient back.
    const int H = 31, W = 31;
    std::vector<float> grad(size_t(H * W * 2)), mask(size_t(H * W)), z(size_t(H * W));
    for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c) {
            const float y = float(r - 15), x = float(c - 15);
            mask[size_t(r * W + c)] = x * x + y * y < 100.0f;
            grad[size_t(r * W + c) * 2] = -2.0f * y / 100.0f, grad[size_t(r * W + c) * 2 + 1] = -2.0f * x / 100.0f;
        }
    ops::gel::masked_poisson(grad.data(), mask.data(), H, W, 200, 1.85f, z.data());
    CHECK(z[size_t(15 * W + 15)] == Approx(1.0).epsilon(0.05));  // the discrete rim sits within a pixel of rho = 10
    CHECK(z[0] == 0.0f);
}

TEST_CASE("the gel's shape ops refuse bad shapes by name", "[op][gel]") {
    Graph g;
    const int f = g.input("f", {4, 5, 3});
    CHECK_THROWS_WITH(ops::gel_gradient(g, f, g.input("e", {4, 6, 3}), g.input("t", {1, 8, 2}), 2, 1, 1),
                      Catch::Contains("empty frame must be [4, 5, 3]"));
    CHECK_THROWS_WITH(ops::gel_gradient(g, f, f, g.input("t2", {2, 8, 2}), 2, 1, 1), Catch::Contains("tables must be [1, 8, 2]"));
    CHECK_THROWS_WITH(ops::gel_gradient(g, g.input("f1", {4, 5}), f, g.input("t3", {1, 8, 2}), 2, 1, 1), Catch::Contains("[H, W, 3]"));
    CHECK_THROWS_WITH(ops::masked_poisson(g, g.input("gr", {4, 5, 2}), g.input("m", {5, 4}), 5, 1.5), Catch::Contains("mask must be [4, 5]"));
    CHECK_THROWS_WITH(ops::masked_poisson(g, g.input("gr2", {4, 5, 2}), g.input("m2", {4, 5}), 5, 2.5), Catch::Contains("omega"));
}
