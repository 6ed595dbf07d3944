#pragma once
// Helpers for the ILU tests (test_ilu_op.cpp, test_ilu_retrieve.cpp): random
// head weights at PyTorch's default init scale, and the 13 inputs of the ops.
#include <cmath>
#include <string>
#include <vector>

#include "engine/graph.h"
#include "engine/model/heads.h"
#include "engine/weights.h"
#include "tests/harness.h"

namespace vtloc::test {

inline WeightStore random_ilu(int64_t C, int64_t H, uint32_t seed) {
    WeightStore w;
    float g = 1.0f / std::sqrt(float(3 * C)), hb = 1.0f / std::sqrt(float(C)), ob = 1.0f / std::sqrt(float(H));
    uint32_t s = seed;
    for (const char* gate : {"convz", "convr", "convq"}) {
        w.add(std::string("ilu.") + gate + ".weight", random_tensor({C, 3 * C}, ++s, -g, g));
        w.add(std::string("ilu.") + gate + ".bias", random_tensor({C}, ++s, -g, g));
    }
    w.add("ilu.head.0.weight", random_tensor({H, C}, ++s, -hb, hb));
    w.add("ilu.head.0.bias", random_tensor({H}, ++s, -hb, hb));
    w.add("ilu.head.2.weight", random_tensor({3, H}, ++s, -ob, ob));
    w.add("ilu.head.2.bias", random_tensor({3}, ++s, -ob, ob));
    return w;
}

// ft [B, C], fp [1, C], iters, then the ten weights: the ilu / ilu_retrieve inputs.
inline std::vector<int> ilu_graph_inputs(Graph& g, const WeightStore& w, int64_t B, int64_t C) {
    std::vector<int> in{g.input("ft", {B, C}), g.input("fp", {1, C}), g.input("iters", {1}, ElemType::I32)};
    for (int v : ilu_weight_inputs(g, w)) in.push_back(v);
    return in;
}

}  // namespace vtloc::test
