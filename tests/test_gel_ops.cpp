// The gel's shape ops (gel_gradient, gel_contact_mask, masked_poisson and its coarse grids'
// mean_pool2 and poisson_prolong) against their CPU
// references (engine/ops/gel_ops.h, gel_mask.h) at odd sizes with fixed seeds, and their shape errors.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "engine/ops/build.h"
#include "engine/ops/gel_mask.h"
#include "engine/ops/gel_ops.h"
#include "tests/harness.h"

using namespace vtloc;

namespace {

HostTensor grey(int64_t H, int64_t W, uint32_t seed) {
    HostTensor t = test::random_tensor({H, W, 3}, seed, 0.0f, 255.0f);
    for (float& v : t.data) v = std::floor(v);
    return t;
}

// A gradient [H, W, 2] of slope 9 where on(r, c), 0 elsewhere, in a direction varying by pixel:
// the 3x3 mean then passes 0.7 wherever a neighbour is on.
template <class F>
HostTensor slope_field(int64_t H, int64_t W, F on) {
    HostTensor g({H, W, 2});
    for (int64_t r = 0; r < H; ++r)
        for (int64_t c = 0; c < W; ++c) {
            const float s = on(r, c) ? 9.0f : 0.0f, a = 0.37f * float(r * W + c);
            g.data[size_t(r * W + c) * 2] = s * std::cos(a), g.data[size_t(r * W + c) * 2 + 1] = s * std::sin(a);
        }
    return g;
}

struct MaskInput {
    const char* what;
    HostTensor grad;
};

// Holes, rings, equal pieces (the tie rule), noise (slopes near the threshold), none and all.
std::vector<MaskInput> mask_inputs(int64_t H, int64_t W, uint32_t seed) {
    const double cy = 0.5 * double(H), cx = 0.5 * double(W);
    auto ring = [&](int64_t r, int64_t c) {
        const double d = std::hypot(double(r) - cy, double(c) - cx);
        return d > 0.2 * double(std::min(H, W)) && d < 0.2 * double(std::min(H, W)) + 2.5;
    };
    auto squares = [&](int64_t r, int64_t c) {  // 5x5 after the mean, none at the far edges
        return r % 11 >= 4 && r % 11 < 7 && c % 11 >= 4 && c % 11 < 7 && r < H - 4 && c < W - 4;
    };
    auto holed = [](int64_t r, int64_t c) {  // 13x13 blocks with holes of 3 and 1 pixels, a pixel's bridge
        const int64_t y = r % 17, x = c % 17;
        return y < 13 && x < 13 && !(y >= 4 && y < 9 && x >= 4 && x < 9) && !(y == 11 && x == 11);
    };
    std::vector<MaskInput> v{{"ring", slope_field(H, W, ring)},
                             {"equal squares", slope_field(H, W, squares)},
                             {"holed blocks", slope_field(H, W, holed)},
                             {"noise", test::random_tensor({H, W, 2}, seed, -1.0f, 1.0f)},
                             {"none", HostTensor({H, W, 2})},
                             {"all", slope_field(H, W, [](int64_t, int64_t) { return true; })}};
    // Rings and blobs of random places and sizes over noise of slope up to 0.8.
    HostTensor mixed = test::random_tensor({H, W, 2}, seed + 1, -0.55f, 0.55f);
    std::mt19937 rng(seed + 2);
    for (int k = 0; k < 6; ++k) {
        const double y = double(rng() % uint32_t(H)), x = double(rng() % uint32_t(W)), rad = 1 + rng() % 9, w = 1 + rng() % 4;
        for (int64_t r = 0; r < H; ++r)
            for (int64_t c = 0; c < W; ++c)
                if (std::abs(std::hypot(double(r) - y, double(c) - x) - rad) < w) mixed.data[size_t(r * W + c) * 2] += 1.5f;
    }
    v.push_back({"rings and blobs over noise", mixed});
    return v;
}

}  // namespace

TEST_CASE("the table cell of a colour change is the shader's floor and clamp", "[gel]") {
    // cell_of avoids a call to floor; over a stride of all float bit patterns (the full sweep ran
    // once: every finite float agrees for these n) and every grey-level difference.
    int64_t checked = 0, wrong = 0;
    for (int n : {2, 3, 64, 256}) {
        auto check = [&](float v) {
            const float q = std::floor((v + 256.0f) * float(n) / 512.0f);
            wrong += vtloc::ops::gel::cell_of(v, n) != int(std::clamp(q, 0.0f, float(n - 1)));
            ++checked;
        };
        for (uint64_t b = 0; b < (uint64_t(1) << 32); b += 9973) {
            const uint32_t u = uint32_t(b);
            float v = 0;
            std::memcpy(&v, &u, sizeof v);
            if (std::isfinite(v)) check(v);
        }
        for (int d = -600; d <= 600; ++d) check(float(d));
    }
    CHECK(checked > 1700000);
    CHECK(wrong == 0);
}

TEST_CASE("gel_gradient matches the CPU reference", "[op][gel][gel_gradient]") {
    struct Case {
        int64_t H, W, n, ty, tx;
    };
    for (const Case& k : {Case{1, 1, 2, 1, 1}, Case{7, 13, 8, 1, 1}, Case{13, 17, 8, 2, 5}, Case{120, 160, 64, 3, 4}}) {
        INFO(k.H << "x" << k.W << " n " << k.n << " tiles " << k.ty << "x" << k.tx);
        Graph g;
        for (double gentle : {0.0, 1.5, 1e5}) {  // tables only, both (half the pixels each), linear only
            INFO("gentle " << gentle);
            Graph g;
            const int out = ops::gel_gradient(g, g.input("frame", {k.H, k.W, 3}), g.input("empty", {k.H, k.W, 3}),
                                              g.input("tables", {k.ty * k.tx, k.n * k.n * k.n, 2}), g.input("linear", {k.H, k.W, 6}),
                                              k.n, k.ty, k.tx, gentle);
            g.output(out, "gradient");
            const uint32_t seed = uint32_t(k.H * 31 + k.n);
            TensorMap in{{"frame", grey(k.H, k.W, seed)}, {"empty", grey(k.H, k.W, seed + 1)},
                         {"tables", test::random_tensor({k.ty * k.tx, k.n * k.n * k.n, 2}, seed + 2, -3.0f, 3.0f)},
                         {"linear", test::random_tensor({k.H, k.W, 6}, seed + 3, -0.01f, 0.01f)}};
            test::run_gpu_and_compare(g, WeightStore{}, in);
        }
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
    const float frame[3] = {7, 7, 7}, linear[6] = {1, 2, 3, 4, 5, 6};
    ops::gel::indentation_gradient(lut.data(), n, 1, 1, 1, 1, frame, frame, linear, 0.0f, 0, 0, gr, gc);
    CHECK((gr == 0.0f && gc == 0.0f));
    // A gentle slope (here none) takes the linear inverse: L d.
    const float empty[3] = {5, 7, 8};
    ops::gel::indentation_gradient(lut.data(), n, 1, 1, 1, 1, frame, empty, linear, 0.5f, 0, 0, gr, gc);
    CHECK(gr == 1 * 2.0f + 2 * 0.0f + 3 * -1.0f);
    CHECK(gc == 4 * 2.0f + 5 * 0.0f + 6 * -1.0f);
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

TEST_CASE("mean_pool2 and poisson_prolong match their CPU references exactly", "[op][gel][mean_pool2][poisson_prolong]") {
    // Exact: the same operations in the same order (a block's count is a power of two).
    for (auto [H, W] : {std::pair<int64_t, int64_t>{1, 1}, {1, 9}, {2, 2}, {7, 13}, {40, 53}, {120, 160}}) {
        for (int64_t C : {0, 1, 2}) {  // 0: an [H, W] input
            INFO(H << "x" << W << " channels " << C);
            const Shape shape = C ? Shape{H, W, C} : Shape{H, W};
            Graph g;
            g.output(ops::mean_pool2(g, g.input("x", shape)), "y");
            const uint32_t seed = uint32_t(H * 100 + W + C);
            const TensorMap out = test::run_gpu_and_compare(g, WeightStore{}, {{"x", test::random_tensor(shape, seed, -2.0f, 2.0f)}}, {0.0, 0.0});
            CHECK(out.at("y").shape[0] == (H + 1) / 2);
        }
        INFO(H << "x" << W << " prolong");
        Graph g;
        g.output(ops::poisson_prolong(g, g.input("coarse", {(H + 1) / 2, (W + 1) / 2}), g.input("mask", {H, W})), "start");
        HostTensor mask({H, W});
        for (int64_t i = 0; i < H * W; ++i) mask.data[size_t(i)] = (i * 5 + 1) % 7 < 5;
        test::run_gpu_and_compare(g, WeightStore{},
                                  {{"coarse", test::random_tensor({(H + 1) / 2, (W + 1) / 2}, uint32_t(H + W), -3.0f, 3.0f)}, {"mask", mask}}, {0.0, 0.0});
    }
    // The plane of slope 1 (z = r + c on the coarse grid, in its pixels) is the plane of slope 1 on
    // the fine grid, z = r + c - 1 (its pixels, its centres), inside the clamped border; and 0
    // outside the mask.
    const int h = 5, w = 6, H = 10, W = 12;
    std::vector<float> zc(size_t(h * w)), mask(size_t(H * W), 1.0f), z0(size_t(H * W));
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) zc[size_t(r * w + c)] = float(r + c);
    mask[size_t(4 * W + 5)] = 0.0f;
    ops::gel::poisson_prolong(zc.data(), h, w, mask.data(), H, W, z0.data());
    for (int r = 1; r < H - 1; ++r)
        for (int c = 1; c < W - 1; ++c) CHECK(z0[size_t(r * W + c)] == (r == 4 && c == 5 ? 0.0f : float(r + c - 1)));
}

TEST_CASE("masked_poisson from a start matches the CPU reference, and a coarse start converges sooner", "[op][gel][masked_poisson]") {
    for (int64_t iterations : {0, 3}) {
        for (auto [H, W] : {std::pair<int64_t, int64_t>{1, 9}, {11, 7}, {40, 53}}) {
            INFO(H << "x" << W << ", " << iterations << " sweeps from a start");
            Graph g;
            g.output(ops::masked_poisson(g, g.input("gradient", {H, W, 2}), g.input("mask", {H, W}), iterations, 1.85, "solve",
                                         g.input("start", {H, W})),
                     "height");
            HostTensor mask({H, W});
            for (int64_t i = 0; i < H * W; ++i) mask.data[size_t(i)] = (i * 7 + 3) % 11 < 8;
            TensorMap in{{"gradient", test::random_tensor({H, W, 2}, uint32_t(H * W), -1.0f, 1.0f)}, {"mask", mask},
                         {"start", test::random_tensor({H, W}, uint32_t(H + W), -5.0f, 5.0f)}};
            const TensorMap out = test::run_gpu_and_compare(g, WeightStore{}, in);
            if (iterations == 0)  // the start where the solve updates, 0 elsewhere
                for (int64_t i = 0; i < H * W; ++i)
                    CHECK(out.at("height").data[size_t(i)] == (mask.data[size_t(i)] > 0.5f ? in.at("start").data[size_t(i)] : 0.0f));
        }
    }
    // A wide paraboloid cap (radius 45 px, depth 1 in z's pixel units): 20 sweeps from zeros stop
    // far short; two coarse grids first (20 sweeps each) come within 2 % of the converged centre.
    const int H = 101, W = 101;
    std::vector<float> grad(size_t(H * W * 2)), mask(size_t(H * W)), plain(size_t(H * W)), coarse(size_t(H * W)), conv(size_t(H * W));
    for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c) {
            const float y = float(r - 50), x = float(c - 50);
            mask[size_t(r * W + c)] = x * x + y * y < 45.0f * 45.0f;
            grad[size_t(r * W + c) * 2] = -2.0f * y / 2025.0f, grad[size_t(r * W + c) * 2 + 1] = -2.0f * x / 2025.0f;
        }
    ops::gel::masked_poisson(grad.data(), mask.data(), H, W, 2000, 1.85f, conv.data());
    ops::gel::masked_poisson_multilevel(grad.data(), mask.data(), H, W, 0, 20, 20, 1.85f, plain.data());
    ops::gel::masked_poisson_multilevel(grad.data(), mask.data(), H, W, 2, 20, 20, 1.85f, coarse.data());
    const size_t centre = size_t(50 * W + 50);
    CHECK(conv[centre] == Approx(1.0).epsilon(0.05));
    CHECK(std::abs(coarse[centre] - conv[centre]) < 0.02f * conv[centre]);
    CHECK(std::abs(plain[centre] - conv[centre]) > 0.2f * conv[centre]);
    CHECK(ops::gel::poisson_levels(120, 160, 5) == 4);  // 60 x 80, 30 x 40, 15 x 20, 8 x 10; not 4 x 5
    CHECK(ops::gel::poisson_levels(15, 200, 3) == 1);   // 8 x 100; not 4 x 50
}

TEST_CASE("gel_contact_mask matches the CPU reference exactly", "[op][gel][gel_contact_mask]") {
    struct Radii {
        int64_t close, open;
    };
    for (auto [H, W] : {std::pair<int64_t, int64_t>{1, 1}, {1, 9}, {7, 13}, {31, 29}, {120, 160}})
        for (Radii rad : {Radii{2, 2}, Radii{0, 0}, Radii{1, 3}}) {
            if (rad.close != 2 && H * W > 1000) continue;  // the other radii at the small sizes only
            for (const MaskInput& m : mask_inputs(H, W, uint32_t(H * 1000 + W))) {
                INFO(H << "x" << W << ", " << m.what << ", close " << rad.close << ", open " << rad.open);
                Graph g;
                g.output(ops::gel_contact_mask(g, g.input("gradient", {H, W, 2}), 0.7, rad.close, rad.open), "mask");
                const TensorMap out = test::run_gpu_and_compare(g, WeightStore{}, {{"gradient", m.grad}}, {0.0, 0.0});
                const std::vector<float>& mask = out.at("mask").data;
                CHECK(std::count_if(mask.begin(), mask.end(), [](float v) { return v != 0.0f && v != 1.0f; }) == 0);
            }
        }
}

TEST_CASE("gel_contact_mask's reference: holes filled, the first of equal pieces, none and all", "[op][gel][gel_contact_mask]") {
    const int H = 40, W = 50;
    auto mask_of = [&](const MaskInput& m) { return ops::gel::contact_mask(m.grad.data.data(), H, W, 0.7f, 2, 2); };
    const std::vector<MaskInput> in = mask_inputs(H, W, 5);
    // Equal 5x5 squares after the 3x3 mean, each opened to the disc of radius 2: the first in
    // raster order, centred at (5, 5). (A piece at the image's edge loses less to the opening:
    // the disc reads only pixels inside the image.)
    const std::vector<uint8_t> sq = mask_of(in[1]);
    for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c) CHECK(sq[size_t(r * W + c)] == ((r - 5) * (r - 5) + (c - 5) * (c - 5) <= 4));
    // The ring comes back as a disc; the blocks' holes are filled.
    const std::vector<uint8_t> ring = mask_of(in[0]), holed = mask_of(in[2]);
    CHECK(ring[size_t(H / 2 * W + W / 2)] == 1);
    for (int r = 5; r < 8; ++r)
        for (int c = 5; c < 8; ++c) CHECK(holed[size_t(r * W + c)] == 1);
    CHECK(holed[size_t(11 * W + 11)] == 1);
    const std::vector<uint8_t> none = mask_of(in[4]), all = mask_of(in[5]);
    CHECK(std::count(none.begin(), none.end(), 1) == 0);
    CHECK(std::count(all.begin(), all.end(), 1) == H * W);
}

TEST_CASE("the gel's shape ops refuse bad shapes by name", "[op][gel]") {
    Graph g;
    const int f = g.input("f", {4, 5, 3});
    const int lin = g.input("lin", {4, 5, 6});
    CHECK_THROWS_WITH(ops::gel_gradient(g, f, g.input("e", {4, 6, 3}), g.input("t", {1, 8, 2}), lin, 2, 1, 1, 0),
                      Catch::Contains("empty frame must be [4, 5, 3]"));
    CHECK_THROWS_WITH(ops::gel_gradient(g, f, f, g.input("t2", {2, 8, 2}), lin, 2, 1, 1, 0), Catch::Contains("tables must be [1, 8, 2]"));
    CHECK_THROWS_WITH(ops::gel_gradient(g, g.input("f1", {4, 5}), f, g.input("t3", {1, 8, 2}), lin, 2, 1, 1, 0), Catch::Contains("[H, W, 3]"));
    CHECK_THROWS_WITH(ops::gel_gradient(g, f, f, g.input("t4", {1, 8, 2}), g.input("lin2", {4, 5, 2}), 2, 1, 1, 0),
                      Catch::Contains("linear inverse must be [4, 5, 6]"));
    CHECK_THROWS_WITH(ops::gel_gradient(g, f, f, g.input("t5", {1, 8, 2}), lin, 2, 1, 1, -1), Catch::Contains("gentle must be >= 0"));
    CHECK_THROWS_WITH(ops::masked_poisson(g, g.input("gr", {4, 5, 2}), g.input("m", {5, 4}), 5, 1.5), Catch::Contains("mask must be [4, 5]"));
    CHECK_THROWS_WITH(ops::masked_poisson(g, g.input("gr2", {4, 5, 2}), g.input("m2", {4, 5}), 5, 2.5), Catch::Contains("omega"));
    CHECK_THROWS_WITH(ops::masked_poisson(g, g.input("gr5", {4, 5, 2}), g.input("m5", {4, 5}), 5, 1.5, "", g.input("s5", {5, 4})),
                      Catch::Contains("start must be [4, 5]"));
    CHECK_THROWS_WITH(ops::mean_pool2(g, g.input("x1", {4})), Catch::Contains("mean_pool2: the input must be [H, W] or [H, W, C], got [4]"));
    CHECK_THROWS_WITH(ops::poisson_prolong(g, g.input("zc", {2, 2}), g.input("m6", {5, 5})),
                      Catch::Contains("poisson_prolong: the coarse answer must be [3, 3] for a [5, 5] mask, got [2, 2]"));
    CHECK_THROWS_WITH(ops::gel_contact_mask(g, g.input("gr3", {4, 5, 3}), 0.7, 2, 2),
                      Catch::Contains("gel_contact_mask: the gradient must be [H, W, 2], got [4, 5, 3]"));
    const int gr = g.input("gr4", {4, 5, 2});
    CHECK_THROWS_WITH(ops::gel_contact_mask(g, gr, 0.7, -1, 2),
                      Catch::Contains("gel_contact_mask: close_radius must be an integer in [0, 64], got -1"));
    CHECK_THROWS_WITH(ops::gel_contact_mask(g, gr, 0.7, 2, 65),
                      Catch::Contains("gel_contact_mask: open_radius must be an integer in [0, 64], got 65"));
    CHECK_THROWS_WITH(ops::gel_contact_mask(g, gr, NAN, 2, 2), Catch::Contains("gel_contact_mask: threshold must be a finite number"));
}
