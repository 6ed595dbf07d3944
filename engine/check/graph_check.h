#pragma once
// Cross-checks a graph on the GPU against the CPU reference, node by node:
// the GPU runs the whole graph once with every value kept (GpuExecutor's
// keep_all), then each node's CPU reference runs on the GPU's own inputs to
// that node, so errors do not accumulate and index ops compare exactly. The
// graph's outputs are also compared with a full CPU reference run (errors
// accumulated: the end-to-end tolerance).
#include <string>
#include <vector>

#include "engine/check/compare.h"
#include "engine/executor.h"

namespace vtloc::rt {
class Context;
}

namespace vtloc::check {

struct NodeCheck {
    std::string node, op;
    std::vector<Shape> input_shapes, output_shapes;
    std::vector<std::string> dispatches;  // "shader spec=[...] texel=0x.. groups=AxBxC" each
    Comparison cmp;                       // over all the node's outputs
    bool has_float = false, has_index = false;
    bool indices_equal = true;
    std::string error;                    // the CPU reference threw on the GPU's inputs
    bool ok() const { return cmp.ok && error.empty(); }
};

struct OutputCheck {
    std::string name;
    Comparison cmp;
};

struct GraphCheck {
    std::vector<NodeCheck> nodes;      // schedule order
    std::vector<OutputCheck> outputs;  // the graph's outputs, end to end
    int first_failure = -1;            // index into nodes
    TensorMap cpu_outputs;             // the full CPU reference run's outputs (a caller may compare another run with them)
    double gpu_ms = 0, cpu_nodes_ms = 0, cpu_full_ms = 0;
    bool ok() const;
};

GraphCheck check_graph(rt::Context& ctx, const Graph& g, const WeightStore& weights, const TensorMap& inputs,
                       Tolerance node_tol = kNodeTolerance, Tolerance end_to_end_tol = kEndToEndTolerance);
// The same on an executor made for g and weights with keep_all: a caller checking one graph on
// many inputs (each frame of a tour) uploads the weights and plans the memory once.
GraphCheck check_graph(GpuExecutor& keep_all_exec, const Graph& g, const WeightStore& weights, const TensorMap& inputs,
                       Tolerance node_tol = kNodeTolerance, Tolerance end_to_end_tol = kEndToEndTolerance);

// One line per dispatch: "shader spec=[a, b, ...] texel=0x3 groups=4x1x1".
std::string dispatch_str(const std::string& shader, const std::vector<uint32_t>& spec, uint32_t texel_bindings,
                         const uint32_t groups[3]);

}  // namespace vtloc::check
