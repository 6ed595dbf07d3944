#pragma once
// The contact heads of SPEC section 2: ILU (GRU iterations) and MCR.
#include <nlohmann/json.hpp>
#include <vector>

#include "engine/graph.h"
#include "engine/weights.h"

namespace vtloc {

// ILU over `iters` iterations from F^t, F^p ([1, C] each). Returns c_1..c_N
// ([1, 3] each, empty for N = 0, where c^p = c_0 = 0). Built from primitive ops.
std::vector<int> build_ilu(Graph& g, const WeightStore& w, int ft, int fp, int iters);

// MCR: c^p = tanh(MLP([F^t, F^p])), hidden sizes from config["mcr"]["hidden"].
int build_mcr(Graph& g, const WeightStore& w, const nlohmann::json& config, int ft, int fp);

}  // namespace vtloc
