#pragma once
// Arithmetic of a graph's GEMM-like nodes (2 FLOPs per multiply-add), for
// GFLOP/s against the device's probe: conv2d, linear and group_linear (the
// point branch's shared MLPs). Other ops count 0.
#include <map>
#include <string>

#include "engine/graph.h"

namespace vtloc::bench {

std::map<std::string, double> node_flops(const Graph& g);

}  // namespace vtloc::bench
