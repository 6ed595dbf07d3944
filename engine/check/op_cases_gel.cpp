// Self-test cases of the gel's shape ops (gel_gradient, gel_contact_mask, masked_poisson with
// mean_pool2 and poisson_prolong):
// grey-level frames, random tables, rings and blobs of slope over noise, a disc-shaped contact.
#include <cmath>
#include <random>

#include "engine/check/op_selftest.h"
#include "engine/ops/build.h"

namespace vtloc::check {

namespace {

// Integral grey levels in [0, 255], as frames hold.
HostTensor grey_frame(int64_t H, int64_t W, uint32_t seed) {
    HostTensor t = random_tensor({H, W, 3}, seed, 0.0f, 255.0f);
    for (float& v : t.data) v = std::floor(v);
    return t;
}

OpCase gradient_case(int64_t H, int64_t W, int64_t n, int64_t ty, int64_t tx, uint32_t seed) {
    OpCase c("gel_gradient", std::to_string(H) + "x" + std::to_string(W) + ", " + std::to_string(ty) + "x" +
                                 std::to_string(tx) + " tables of " + std::to_string(n) + "^3");
    const int g = ops::gel_gradient(c.g, c.input("frame", grey_frame(H, W, seed)), c.input("empty", grey_frame(H, W, seed + 1)),
                                    c.input("tables", random_tensor({ty * tx, n * n * n, 2}, seed + 2, -3.0f, 3.0f)),
                                    c.input("linear", random_tensor({H, W, 6}, seed + 3, -0.01f, 0.01f)), n, ty, tx, 1.5);
    c.output(g, "gradient");
    return c;
}

OpCase poisson_case(int64_t H, int64_t W, int64_t iterations, uint32_t seed) {
    OpCase c("masked_poisson", std::to_string(H) + "x" + std::to_string(W) + ", " + std::to_string(iterations) + " sweeps");
    HostTensor mask({H, W});
    for (int64_t r = 0; r < H; ++r)
        for (int64_t col = 0; col < W; ++col)
            mask.data[size_t(r * W + col)] = std::hypot(double(r) - 0.45 * H, double(col) - 0.55 * W) < 0.35 * double(std::min(H, W));
    c.output(ops::masked_poisson(c.g, c.input("gradient", random_tensor({H, W, 2}, seed, -1.0f, 1.0f)), c.input("mask", mask),
                                 iterations, 1.85),
             "height");
    return c;
}

// The solve from a coarse start: gradient and mask halved (mean_pool2), solved there, the answer
// prolonged (poisson_prolong) as the full grid's start.
OpCase coarse_start_case(int64_t H, int64_t W, int64_t iterations, uint32_t seed) {
    OpCase c("masked_poisson", std::to_string(H) + "x" + std::to_string(W) + " from a coarse start (mean_pool2, poisson_prolong), " +
                                   std::to_string(iterations) + " sweeps a grid");
    HostTensor mask({H, W});
    for (int64_t r = 0; r < H; ++r)
        for (int64_t col = 0; col < W; ++col)
            mask.data[size_t(r * W + col)] = std::hypot(double(r) - 0.5 * H, double(col) - 0.4 * W) < 0.4 * double(std::min(H, W));
    const int grad = c.input("gradient", random_tensor({H, W, 2}, seed, -1.0f, 1.0f)), m = c.input("mask", mask);
    const int grad2 = ops::mean_pool2(c.g, grad), m2 = ops::mean_pool2(c.g, m);
    const int coarse = ops::masked_poisson(c.g, grad2, m2, iterations, 1.85);
    c.output(ops::masked_poisson(c.g, grad, m, iterations, 1.85, "", ops::poisson_prolong(c.g, coarse, m)), "height");
    return c;
}

OpCase mean_pool2_case(int64_t H, int64_t W, int64_t C, uint32_t seed) {
    OpCase c("mean_pool2", std::to_string(H) + "x" + std::to_string(W) + "x" + std::to_string(C));
    c.output(ops::mean_pool2(c.g, c.input("x", random_tensor({H, W, C}, seed, -2.0f, 2.0f))), "y");
    c.tol = {0.0, 0.0};  // the same sums in the same order, over a power of two
    return c;
}

OpCase prolong_case(int64_t H, int64_t W, uint32_t seed) {
    OpCase c("poisson_prolong", std::to_string(H) + "x" + std::to_string(W));
    HostTensor mask({H, W});
    for (int64_t i = 0; i < H * W; ++i) mask.data[size_t(i)] = (i * 5 + 1) % 7 < 5;
    c.output(ops::poisson_prolong(c.g, c.input("coarse", random_tensor({(H + 1) / 2, (W + 1) / 2}, seed, -3.0f, 3.0f)), c.input("mask", mask)),
             "start");
    return c;
}

// Rings and blobs of slope over noise near the threshold: holes, several pieces, a fringe.
OpCase mask_case(int64_t H, int64_t W, int64_t close_radius, int64_t open_radius, uint32_t seed) {
    OpCase c("gel_contact_mask", std::to_string(H) + "x" + std::to_string(W) + ", close " + std::to_string(close_radius) + ", open " +
                                     std::to_string(open_radius));
    HostTensor grad = random_tensor({H, W, 2}, seed, -0.55f, 0.55f);
    std::mt19937 rng(seed + 1);
    for (int k = 0; k < 8; ++k) {
        const double y = double(rng() % uint32_t(H)), x = double(rng() % uint32_t(W)), rad = 1 + rng() % 12, w = 1 + rng() % 4;
        for (int64_t r = 0; r < H; ++r)
            for (int64_t col = 0; col < W; ++col)
                if (std::abs(std::hypot(double(r) - y, double(col) - x) - rad) < w) grad.data[size_t(r * W + col) * 2] += 1.5f;
    }
    c.output(ops::gel_contact_mask(c.g, c.input("gradient", grad), 0.7, close_radius, open_radius), "mask");
    c.tol = {0.0, 0.0};  // 0/1: the same fp32 slopes on both sides, then integer steps
    return c;
}

}  // namespace

std::vector<OpCase> gel_cases(const rt::DeviceInfo&) {
    return {gradient_case(13, 17, 8, 2, 3, 11), gradient_case(120, 160, 16, 3, 4, 12), mask_case(37, 29, 1, 3, 14),
            mask_case(120, 160, 2, 2, 15), poisson_case(23, 31, 20, 13), coarse_start_case(37, 45, 10, 16),
            mean_pool2_case(37, 45, 2, 17), prolong_case(37, 45, 18)};
}

}  // namespace vtloc::check
