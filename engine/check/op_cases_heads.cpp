// Self-test cases: disentangle (whole and split into row chunks), gma_decode,
// chamfer (one set and a batch), ilu (1/4/8/16 lanes per row, register-resident), ilu_step, topk (ties;
// a batch with its heat-maps), heatmap (with and without symmetry), retrieve and ilu_retrieve (both paths); the shapes of tests/test_gma_ops.cpp,
// test_ilu_op.cpp and test_topk_heatmap.cpp.
#include <cmath>

#include "engine/check/op_selftest.h"
#include "engine/model/gma.h"
#include "engine/model/heads.h"
#include "engine/model/post.h"
#include "engine/ops/common.h"
#include "engine/ops/build.h"

namespace vtloc::check {

namespace {

OpCase disentangle_case(int64_t rows, int64_t K, int64_t J, int64_t L, int64_t chunk_rows, uint32_t seed) {
    const int64_t chunks = (K + chunk_rows - 1) / chunk_rows;
    OpCase c("disentangle", std::to_string(rows) + "x" + std::to_string(K) + " by [" + std::to_string(K) + ", " +
                                std::to_string(J) + ", " + std::to_string(L) + "] in " + std::to_string(chunks) +
                                " row chunk" + (chunks > 1 ? "s" : ""));
    c.w.add("wd", random_tensor({K, J, L}, seed + 1, -0.3f, 0.3f));
    std::vector<int> in{c.input("x", random_tensor({rows, K}, seed, -2.0f, 2.0f))};
    for (const std::string& n : split_weight_rows(c.w, "wd", uint64_t(chunk_rows * J * L * 4)))
        in.push_back(c.g.weight(n, c.w.get(n).shape));
    c.output(ops::disentangle(c.g, in, ops::kActLeaky, 0.01), "y");
    return c;
}

void add_ilu_weights(OpCase& c, int64_t C, int64_t H, uint32_t seed) {
    const float g = 1.0f / std::sqrt(float(3 * C)), hb = 1.0f / std::sqrt(float(C)), ob = 1.0f / std::sqrt(float(H));
    uint32_t s = seed;
    for (const char* gate : {"convz", "convr", "convq"}) {
        c.w.add(std::string("ilu.") + gate + ".weight", random_tensor({C, 3 * C}, ++s, -g, g));
        c.w.add(std::string("ilu.") + gate + ".bias", random_tensor({C}, ++s, -g, g));
    }
    c.w.add("ilu.head.0.weight", random_tensor({H, C}, ++s, -hb, hb));
    c.w.add("ilu.head.0.bias", random_tensor({H}, ++s, -hb, hb));
    c.w.add("ilu.head.2.weight", random_tensor({3, H}, ++s, -ob, ob));
    c.w.add("ilu.head.2.bias", random_tensor({3}, ++s, -ob, ob));
}

// The ten weights after F^t, F^p and N: the ilu / ilu_retrieve inputs.
void add_ilu_weight_inputs(OpCase& c, std::vector<int>& in) {
    for (const char* n : {"ilu.convz.weight", "ilu.convz.bias", "ilu.convr.weight", "ilu.convr.bias", "ilu.convq.weight",
                          "ilu.convq.bias", "ilu.head.0.weight", "ilu.head.0.bias", "ilu.head.2.weight", "ilu.head.2.bias"})
        in.push_back(c.g.weight(n, c.w.get(n).shape));
}

OpCase ilu_case(int64_t C, int64_t H, int iters, bool stepped, double lanes) {
    OpCase c(stepped ? "ilu_step" : "ilu", "C " + std::to_string(C) + ", hidden " + std::to_string(H) + ", N " +
                                               std::to_string(iters) +
                                               (lanes > 0 ? ", " + std::to_string(int(lanes)) + " lanes per row" : ""));
    add_ilu_weights(c, C, H, uint32_t(C) + 3);
    int ft = c.input("ft", random_tensor({1, C}, 7, -2.0f, 2.0f)), fp = c.input("fp", random_tensor({1, C}, 8, -2.0f, 2.0f));
    int iters_in = c.input("iters", ilu_iters_input(iters, iters));
    if (lanes > 0) {
        std::vector<int> in{ft, fp, iters_in};
        add_ilu_weight_inputs(c, in);
        c.output(ops::ilu(c.g, in, iters, "", int(lanes))[0], "c");
        return c;
    }
    IluOutputs o = (stepped ? build_ilu_stepped : build_ilu)(c.g, c.w, ft, fp, iters_in, iters);
    c.output(o.contact, "contact");
    c.output(o.c, "c");
    return c;
}

}  // namespace

std::vector<OpCase> head_cases(const rt::DeviceInfo&) {
    std::vector<OpCase> v;
    v.push_back(disentangle_case(1, 37, 13, 7, 10, 2));
    v.push_back(disentangle_case(3, 64, 129, 5, 64, 3));
    v.push_back(disentangle_case(1, 256, 300, 64, 97, 4));

    OpCase dec("gma_decode", "[1, 37, 6] with a zero normal and one below the clamp");
    HostTensor o = random_tensor({1, 37, 6}, 7, -3.0f, 3.0f);
    for (int k = 3; k < 6; ++k) o.data[size_t(6 * 5 + k)] = 0.0f;
    for (int k = 3; k < 6; ++k) o.data[size_t(6 * 6 + k)] = k == 3 ? 1e-8f : 0.0f;
    dec.output(dec.g.add1("gma_decode", {dec.input("o", o)}), "y");
    v.push_back(std::move(dec));

    for (auto [a, b] : {std::pair<Shape, Shape>{{37, 3}, {53, 3}}, {{1, 300, 6}, {257, 6}}, {{1000, 3}, {7, 3}},
                        {{5, 300, 6}, {257, 6}}}) {  // the last: a batch of 5 sets
        OpCase c("chamfer", shape_str(a) + " vs " + shape_str(b));
        std::vector<int> out = c.g.add("chamfer", {c.input("a", random_tensor(a, 1)), c.input("b", random_tensor(b, 2))});
        c.output(out[0], "chamfer");
        c.output(out[1], "mins");
        v.push_back(std::move(c));
    }

    v.push_back(ilu_case(37, 19, 7, false, 0));
    v.push_back(ilu_case(301, 33, 3, false, 0));
    // C and H multiples of 4: the register-resident shader (ilu_wave) where the device has shuffles.
    v.push_back(ilu_case(64, 32, 16, false, 0));
    v.push_back(ilu_case(20, 12, 9, false, 0));
    for (double lanes : {1.0, 4.0, 8.0, 16.0}) v.push_back(ilu_case(37, 19, 5, false, lanes));  // 4, 8: shuffles where they fit
    v.push_back(ilu_case(37, 19, 7, true, 0));

    for (int64_t M : {37, 2049, 100003}) {
        for (bool ties : {false, true}) {
            const int k = M > 5000 ? 64 : 5;
            OpCase c("topk", std::to_string(M) + " candidates, K " + std::to_string(k) + (ties ? ", many exact ties" : ""));
            HostTensor cand = random_tensor({M, 3}, uint32_t(M), ties ? -4.0f : -1.0f, ties ? 4.0f : 1.0f);
            if (ties)
                for (float& x : cand.data) x = std::round(x) / 4.0f;
            HostTensor centre = ties ? HostTensor({1, 3}, {0, 0, 0}) : HostTensor({3}, {0.1f, -0.2f, 0.05f});
            std::vector<int> out = ops::topk(c.g, c.input("c", centre), c.input("cand", cand), k);
            c.output(out[0], "index");
            c.output(out[1], "score");
            c.tol = {0.0, 0.0};  // same fp32 roundings on both sides
            v.push_back(std::move(c));
        }
    }
    {
        OpCase c("topk", "a batch of 7 contacts, 2049 candidates, K 64, and their heat-maps on 513 points");
        const int cand = c.input("cand", random_tensor({2049, 3}, 11));
        std::vector<int> out = ops::topk(c.g, c.input("c", random_tensor({7, 3}, 12)), cand, 64);
        c.output(out[0], "index");
        c.output(out[1], "score");
        c.output(ops::heatmap(c.g, c.input("cloud", random_tensor({513, 6}, 13)), cand, out[0], -1), "heat");
        v.push_back(std::move(c));
    }

    for (bool sym : {false, true}) {  // one dispatch without symmetry, the two ops' shaders with it
        OpCase c("retrieve", std::string("a batch of 3 contacts, 301 candidates, K 5, heat-maps on 1037 points") +
                                 (sym ? ", symmetry order 3" : ""));
        const int sym_in = sym ? c.input("sym", symmetry_transforms({0.1, 0.0, -0.1}, {0.2, 1.0, 0.1}, 3)) : -1;
        std::vector<int> out = ops::retrieve(c.g, c.input("c", random_tensor({3, 3}, 14)), c.input("cand", random_tensor({301, 3}, 15)),
                                             c.input("cloud", random_tensor({1037, 6}, 16)), sym_in, 5);
        c.output(out[0], "index");
        c.output(out[1], "score");
        c.output(out[2], "heat");
        v.push_back(std::move(c));
    }

    for (bool sym : {false, true}) {  // one dispatch without symmetry, the two ops' shaders with it
        OpCase c("ilu_retrieve", std::string("a batch of 3 touches, C 64, hidden 32, N 16, 301 candidates, K 5, ") +
                                     "heat-maps on 1037 points" + (sym ? ", symmetry order 3" : ""));
        add_ilu_weights(c, 64, 32, 67);
        std::vector<int> in{c.input("ft", random_tensor({3, 64}, 7, -2.0f, 2.0f)),
                            c.input("fp", random_tensor({1, 64}, 8, -2.0f, 2.0f)), c.input("iters", ilu_iters_input(16, 16))};
        add_ilu_weight_inputs(c, in);
        const int sym_in = sym ? c.input("sym", symmetry_transforms({0.0, 0.0, 0.0}, {0.2, 1.0, 0.1}, 3)) : -1;
        std::vector<int> out = ops::ilu_retrieve(c.g, in, 16, c.input("cand", random_tensor({301, 3}, 15, -0.5f, 0.5f)),
                                                 c.input("cloud", random_tensor({1037, 6}, 16, -0.5f, 0.5f)), sym_in, 5);
        const char* names[] = {"c", "contact", "index", "score", "heat"};
        for (int i = 0; i < 5; ++i) c.output(out[size_t(i)], names[i]);
        v.push_back(std::move(c));
    }

    for (bool sym : {false, true}) {
        OpCase c("heatmap", std::string("1037 points, 301 candidates, 5 centres (one repeated)") +
                                (sym ? ", symmetry order 5" : ""));
        std::vector<int32_t> idx{17, 3, 300, 0, 17};
        std::vector<int> in{c.input("cloud", random_tensor({1037, sym ? 3 : 6}, 2)), c.input("cand", random_tensor({301, 3}, 1)),
                            c.input("index", HostTensor::from_ints({5}, idx))};
        if (sym) in.push_back(c.input("sym", symmetry_transforms({0.1, -0.2, 0.0}, {0.3, 1.0, -0.2}, 5)));
        c.output(c.g.add1("heatmap", in), "heat");
        v.push_back(std::move(c));
    }

    return v;
}

}  // namespace vtloc::check
