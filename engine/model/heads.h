#pragma once
// The contact heads of SPEC section 2: ILU (GRU iterations) and MCR.
#include <vector>

#include "engine/graph.h"
#include "engine/model/model_config.h"
#include "engine/weights.h"

namespace vtloc {

// ILU from F^t, F^p ([1, C] each), fused into one op (engine/ops/ilu.cpp). F^t may
// also be [B, C]: B states in the one dispatch, c [B, max_iters, 3], contact [B, 3].
// `iters` is a graph value, I32 [1], holding N (0..max_iters) at run time, so N
// changes without rebuilding; max_iters is 0..limits::kMaxIters. c: [max_iters, 3] = c_1..c_N
// then zero rows; contact: [3] = c^p = c_N (0 for N = 0).
struct IluOutputs {
    int c = -1;
    int contact = -1;
};
IluOutputs build_ilu(Graph& g, const WeightStore& w, int ft, int fp, int iters, int max_iters);
// The ILU's ten weights as graph values, in the order the ilu ops take them after
// ft, fp and iters (convz, convr, convq weight and bias, then the head's two layers).
std::vector<int> ilu_weight_inputs(Graph& g, const WeightStore& w);

// The same head recorded as one ilu_step dispatch per iteration (1..64
// max_iters), nodes "ilu.step0", "ilu.step1", ...: slower, but a profiled run
// has a timestamp between iterations. Same outputs as build_ilu.
IluOutputs build_ilu_stepped(Graph& g, const WeightStore& w, int ft, int fp, int iters, int max_iters);

// build_ilu followed by the top-K and heat-map on its contact as one node, "ilu"
// (engine/ops/ilu_retrieve.cpp: one dispatch where both fit their register
// shaders). symmetry: -1 for none.
struct IluRetrieveOutputs {
    IluOutputs ilu;
    int index = -1, score = -1, heat = -1;
};
IluRetrieveOutputs build_ilu_retrieve(Graph& g, const WeightStore& w, int ft, int fp, int iters, int max_iters,
                                      int candidates, int cloud, int symmetry, int64_t k);

// The run-time input for `iters`; throws unless 0 <= n <= max_iters.
HostTensor ilu_iters_input(int n, int max_iters);

// MCR: c^p = tanh(MLP([F^t, F^p])), hidden sizes from config.mcr_hidden.
int build_mcr(Graph& g, const WeightStore& w, const ModelConfig& config, int ft, int fp);

}  // namespace vtloc
