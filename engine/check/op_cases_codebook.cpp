// Self-test cases of render-and-compare's ops (codebook_render, codebook_window_min
// and codebook_score, the score's case running both):
// random surface points binned as the codebook bins them, random height maps and
// a non-negative measured map.
#include <cmath>
#include <random>

#include "engine/check/op_selftest.h"
#include "engine/ops/build.h"
#include "engine/ops/codebook_bins.h"
#include "engine/ops/codebook_math.h"

namespace vtloc::check {

namespace {

OpCase render_case(int64_t S, int64_t D, int64_t G, uint32_t seed) {
    OpCase c("codebook_render", std::to_string(S) + " samples, " + std::to_string(D) + " points, " + std::to_string(G) + "^2 cells");
    std::mt19937 rng(seed);
    std::vector<float> dense(size_t(6 * D)), samples(size_t(9 * S));
    for (int64_t i = 0; i < D; ++i) {  // points on a 15 mm sphere, each with its unit normal
        float u[6];
        random_unit_pair(rng, u);
        for (int k = 0; k < 3; ++k) dense[size_t(6 * i + k)] = 15 * u[k], dense[size_t(6 * i + 3 + k)] = u[k];
    }
    for (int64_t i = 0; i < S; ++i) {  // samples: a point, its normal and a tangent
        float u[6];
        random_unit_pair(rng, u);
        for (int k = 0; k < 3; ++k)
            samples[size_t(9 * i + k)] = 15 * u[k], samples[size_t(9 * i + 3 + k)] = u[k], samples[size_t(9 * i + 6 + k)] = u[3 + k];
    }
    const ops::book::BinnedPoints b = ops::book::bin_points(dense, 9.0);
    ops::CodebookRender p;
    p.G = G, p.cell = 0.9, p.splat = 0.7, p.cap = 5, p.coarse = b.coarse, p.max_bin = b.max_bin;
    for (int k = 0; k < 3; ++k) p.origin[k] = b.origin[k], p.dims[k] = b.dims[k];
    const int64_t NB = b.dims[0] * b.dims[1] * b.dims[2];
    c.output(ops::codebook_render(c.g, c.input("samples", HostTensor({S, 9}, samples)), c.input("points", HostTensor({D, 6}, b.points)),
                                  c.input("bins", HostTensor::from_ints({NB, 2}, b.bins)), p),
             "heights");
    return c;
}

// Random maps as the scorer reads them: their bilinear quads [S, 4 (G+1)^2].
HostTensor random_quads(int64_t S, int64_t G, uint32_t seed) {
    const HostTensor maps = random_tensor({S, G * G}, seed, -1.0f, 3.0f);
    return HostTensor({S, 4 * (G + 1) * (G + 1)}, ops::book::quads_of_maps(maps.data.data(), S, int32_t(G), 8.0f));
}

HostTensor spin_table(int64_t NS) { return HostTensor({NS, 2}, ops::book::spin_table(int32_t(NS))); }

std::string book_label(int64_t S, int64_t G, int64_t NS, int64_t R, int64_t C) {
    return std::to_string(S) + " maps of " + std::to_string(G) + "^2, " + std::to_string(NS) + " spins, " + std::to_string(R) + "x" +
           std::to_string(C) + " window";
}

OpCase window_min_case(int64_t S, int64_t G, int64_t NS, int64_t R, int64_t C, uint32_t seed) {
    OpCase c("codebook_window_min", book_label(S, G, NS, R, C));
    c.output(ops::codebook_window_min(c.g, c.input("quads", random_quads(S, G, seed)), c.input("spins", spin_table(NS)), R, C, 1.0, 0.996, 8.0),
             "wmin");
    return c;
}

OpCase score_case(int64_t S, int64_t G, int64_t NS, int64_t R, int64_t C, bool quadratic, uint32_t seed) {
    OpCase c("codebook_score", book_label(S, G, NS, R, C) + (quadratic ? ", quadratic" : ""));
    HostTensor meas = random_tensor({R, C}, seed + 1, -0.3f, 1.2f);
    for (float& v : meas.data) v = std::max(0.0f, v);
    const int quads = c.input("quads", random_quads(S, G, seed)), sp = c.input("spins", spin_table(NS));
    const int wmin = ops::codebook_window_min(c.g, quads, sp, R, C, 1.0, 0.996, 8.0);
    const int press = c.input("press", HostTensor({1}, {ops::book::measured_press(meas.data.data(), int32_t(R * C), 95)}));
    c.output(ops::codebook_score(c.g, quads, sp, c.input("measured", meas), wmin, press, 1.0, 0.996, 8.0, 1.5, quadratic), "term");
    return c;
}

}  // namespace

std::vector<OpCase> codebook_cases(const rt::DeviceInfo&) {
    return {render_case(7, 4001, 13, 21), render_case(33, 12000, 27, 22), window_min_case(5, 27, 36, 15, 20, 25),
            score_case(11, 27, 36, 15, 20, false, 23), score_case(7, 27, 36, 15, 20, true, 26),
            score_case(3, 5, 7, 1, 3, false, 24)};
}

}  // namespace vtloc::check
