// Self-test cases of the multi-touch filter's ops (tests/test_pose_ops.cpp):
// pose_evidence on a random scene (terms with geometry, with fields, both; some
// poses leave the grid, some cells are empty; tables as texels and in storage buffers), then log_softmax, spin_marginal
// and expected_distance on its score; field_slack on random fields.
#include <cmath>
#include <random>

#include "engine/check/op_selftest.h"
#include "engine/ops/build.h"
#include "engine/ops/pose_evidence.h"

namespace vtloc::check {

namespace {

// interleave: hypotheses an invocation runs side by side (0: the device's; 3 on a CPU driver, 1
// on a GPU), forced to check the other's code on this device too.
OpCase pose_case(int64_t S, int64_t NS, int64_t K, uint32_t seed, ops::BufferPath path, int64_t interleave = 0) {
    OpCase c("pose_evidence", std::to_string(S) + " samples x " + std::to_string(NS) + " spins, " + std::to_string(K) +
                                  " terms, " + ops::path_name(path) +
                                  (interleave ? ", " + std::to_string(interleave) + " hypotheses an invocation" : ""));
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-4.0f, 4.0f);
    const int64_t D = 2 * S + 3, V = 6 * 5 * 7, F = 2;
    HostTensor samples({S, 9}), dense({D, 8}), spins({NS, 2}), terms({K, 16}), fields({F, S * NS});
    for (int64_t s = 0; s < S; ++s) {
        float* r = &samples.data[size_t(s * 9)];
        for (int i = 0; i < 3; ++i) r[i] = u(rng);
        random_unit_pair(rng, r + 3);
    }
    for (int64_t i = 0; i < D; ++i) {
        float* r = &dense.data[size_t(i * 8)], t[6];
        random_unit_pair(rng, t);
        for (int k = 0; k < 3; ++k) r[k] = u(rng), r[4 + k] = t[k];
        r[3] = float(int64_t(rng() % uint32_t(S + 1)) - 1);  // the point's sample (-1: none)
        r[7] = 1e30f;                                      // padding: never read
    }
    std::vector<int32_t> cells(size_t(2 * V));  // the nearest dense point and its far-face counterpart
    for (int32_t& c : cells) c = int32_t(rng() % uint32_t(D + 1)) - 1;
    for (int64_t j = 0; j < NS; ++j)
        spins.data[size_t(2 * j)] = float(std::cos(2 * M_PI * double(j) / double(NS))),
        spins.data[size_t(2 * j + 1)] = float(std::sin(2 * M_PI * double(j) / double(NS)));
    for (int64_t k = 0; k < K; ++k) {
        float* r = &terms.data[size_t(k * 16)], a[6];
        random_unit_pair(rng, a);  // a rotation from two orthonormal columns and their cross product
        const float z[3] = {a[1] * a[5] - a[2] * a[4], a[2] * a[3] - a[0] * a[5], a[0] * a[4] - a[1] * a[3]};
        for (int i = 0; i < 3; ++i) r[3 * i] = a[i], r[3 * i + 1] = a[3 + i], r[3 * i + 2] = z[i];
        for (int i = 0; i < 3; ++i) r[9 + i] = u(rng);
        r[12] = k % 3 == 1 ? 0.0f : 0.8f;
        r[13] = 0.25f;
        r[14] = float(int64_t(k % 3) - 1);
        r[15] = 0.7f;
    }
    std::uniform_real_distribution<float> lf(-20.0f, 0.0f);
    for (float& x : fields.data) x = lf(rng);
    ops::PoseEvidence p;
    p.voxel = 1.5;
    p.origin[0] = -4.5, p.origin[1] = -3.75, p.origin[2] = -5.25;
    p.dims[0] = 6, p.dims[1] = 5, p.dims[2] = 7;
    p.own_field = 1;
    p.path = path;
    p.interleave = interleave;
    samples = HostTensor({S, 12}, ops::pose::evidence_samples(samples.data));
    int score = ops::pose_evidence(c.g, c.input("samples", samples), c.input("dense", dense),
                                   c.input("cells", HostTensor::from_ints({V, 2}, cells)), c.input("spins", spins),
                                   c.input("terms", terms), c.input("fields", fields), p);
    c.output(score, "score");
    return c;
}

// The three reductions in a chain, filed under `op` (the cases are small).
OpCase reduce_case(const char* op, int64_t S, int64_t NS, uint32_t seed, ops::BufferPath path = ops::BufferPath::Texel) {
    OpCase c(op, std::to_string(S) + " x " + std::to_string(NS) + " spins: log_softmax, spin_marginal, expected_distance, " +
                     ops::path_name(path));
    std::vector<int> lp = ops::log_softmax(c.g, c.input("score", random_tensor({S * NS}, seed, -30.0f, 5.0f)), "", path);
    int m = ops::spin_marginal(c.g, lp[1], NS, "", path);
    c.output(lp[0], "log");
    c.output(m, "marginal");
    const int pts = c.input("pts", random_tensor({S, 3}, seed + 1, -50.0f, 50.0f));
    c.output(ops::expected_distance(c.g, pts, m, c.input("answers", random_tensor({(S + 2) / 3, 3}, seed + 2, -60.0f, 60.0f)),
                                    "", true, path),
             "cost");
    return c;
}

// field_slack on random fields and a random neighbour table (0..KN neighbours a sample).
OpCase slack_case(int64_t F, int64_t S, int64_t KN, int64_t NS, uint32_t seed) {
    OpCase c("field_slack", std::to_string(F) + " fields, " + std::to_string(S) + " samples x " + std::to_string(NS) +
                                " spins, " + std::to_string(KN) + " neighbours");
    HostTensor w({F, 2});
    for (int64_t f = 0; f < F; ++f) w.data[size_t(2 * f)] = f % 2 ? 0.0f : 0.4f, w.data[size_t(2 * f + 1)] = f % 3 ? 3.0f : 0.0f;
    const int fields = c.input("fields", random_tensor({F, S * NS}, seed, -30.0f, 0.0f));
    c.output(ops::field_slack(c.g, fields, c.input("neighbours", random_slack_neighbours(S, KN, NS, seed + 1)),
                              c.input("widths", w), NS),
             "fields");
    return c;
}

}  // namespace

void random_unit_pair(std::mt19937& rng, float* r) {
    std::normal_distribution<float> g;
    float a[3] = {g(rng), g(rng), g(rng)}, b[3] = {g(rng), g(rng), g(rng)};
    float la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (float& x : a) x /= la;
    float d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    for (int i = 0; i < 3; ++i) b[i] -= d * a[i];
    float lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    for (int i = 0; i < 3; ++i) r[i] = a[i], r[3 + i] = b[i] / lb;
}

HostTensor random_slack_neighbours(int64_t S, int64_t KN, int64_t NS, uint32_t seed) {
    std::mt19937 rng(seed);
    HostTensor nb({S, KN, 3});
    for (int64_t s = 0; s < S; ++s) {
        const int64_t n = int64_t(rng() % uint32_t(KN + 1));
        for (int64_t k = 0; k < KN; ++k) {
            float* r = &nb.data[size_t((s * KN + k) * 3)];
            r[0] = k < n ? float(rng() % uint32_t(S)) : -1.0f;
            r[1] = float(rng() % 1000) / 100.0f;
            r[2] = float(rng() % uint32_t(NS));
        }
    }
    return nb;
}

std::vector<OpCase> track_cases(const rt::DeviceInfo&) {
    std::vector<OpCase> v;
    v.push_back(pose_case(61, 36, 6, 3, ops::BufferPath::Texel));
    v.push_back(pose_case(7, 5, 0, 4, ops::BufferPath::Texel));
    v.push_back(pose_case(61, 36, 6, 3, ops::BufferPath::Storage));
    for (int64_t m : {1, 3}) v.push_back(pose_case(61, 36, 6, 9, ops::BufferPath::Texel, m));
    v.push_back(pose_case(53, 12, 4, 10, ops::BufferPath::Storage, 5));  // 636 hypotheses: the last invocation's partly past H
    v.push_back(reduce_case("log_softmax", 1031, 12, 5));
    v.push_back(reduce_case("spin_marginal", 300, 36, 6));
    v.push_back(reduce_case("expected_distance", 77, 1, 7));
    v.push_back(reduce_case("spin_marginal", 300, 36, 8, ops::BufferPath::Storage));
    v.push_back(slack_case(4, 97, 12, 36, 8));
    return v;
}

}  // namespace vtloc::check
