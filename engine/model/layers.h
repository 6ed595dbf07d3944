#pragma once
// Graph-building helpers for the PyTorch layers the model files share.
#include <string>

#include "engine/graph.h"
#include "engine/weights.h"

namespace vtloc {

// Linear `prefix.weight` [out, in] (+ `prefix.bias` if present) on x [..., in],
// with an activation fused into the GEMM (ops::Act code).
int add_linear(Graph& g, const WeightStore& w, const std::string& prefix, int x, uint32_t act = 0,
               double slope = 0.01);

// PyTorch nn.Sequential(Linear, ReLU, Linear, ReLU, ..., Linear): Linear layers
// named prefix.0, prefix.2, ...; `layers` of them, ReLU between, none after the last.
int add_mlp(Graph& g, const WeightStore& w, const std::string& prefix, int x, int layers,
            uint32_t final_act = 0);

}  // namespace vtloc
