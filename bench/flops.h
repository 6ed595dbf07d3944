#pragma once
// Arithmetic of a graph's GEMM-like nodes (2 FLOPs per multiply-add), for
// GFLOP/s against the device's probe: conv2d, linear and group_linear (the
// point branch's shared MLPs). Other ops count 0.
#include <map>
#include <string>

#include "engine/executor.h"
#include "engine/graph.h"
#include "engine/weights.h"

namespace vtloc::bench {

// The indices of every ball_query node, by node name, from the CPU references of
// the nodes they depend on alone (FPS, ball query: cheap beside the MLPs).
std::map<std::string, HostTensor> ball_indices(const Graph& g, const WeightStore& w, const TensorMap& inputs);

// A group_linear that skips ball padding (param pad) counts the rows it must
// compute (the real rows of its ball, from `balls`) instead of every row: the
// work a skipping layer does lies between the two, so its GFLOP/s is a lower bound.
std::map<std::string, double> node_flops(const Graph& g, const std::map<std::string, HostTensor>& balls = {});

}  // namespace vtloc::bench
