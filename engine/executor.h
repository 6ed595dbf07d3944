#pragma once
// Runs a Graph: on the CPU with the reference implementations (the oracle),
// or on the GPU as one pre-recorded command buffer submitted per run.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "engine/graph.h"
#include "engine/tensor.h"
#include "engine/resident_weights.h"
#include "engine/weights.h"
#include "runtime/memory.h"
#include "runtime/sequence.h"

namespace vtloc {

namespace rt {
class Context;
}

using TensorMap = std::map<std::string, HostTensor>;

// Checks that `inputs` holds exactly the graph's inputs with their shapes.
void check_inputs(const Graph& g, const TensorMap& inputs);

// With `node_ms`, also the wall time of each node's reference run, in
// schedule order (the CPU backend's equivalent of GPU timestamps).
struct NodeMs {
    std::string label;
    double ms = 0.0;
};
TensorMap run_cpu(const Graph& g, const WeightStore& weights, const TensorMap& inputs,
                  std::vector<NodeMs>* node_ms = nullptr);
// The CPU reference of only the nodes that the values `wanted` depend on; returns
// those values by id. Inputs and weights that no such node reads may be absent
// (the benches read a graph's ball indices without running its MLPs).
std::map<int, HostTensor> run_cpu_values(const Graph& g, const WeightStore& weights, const TensorMap& inputs,
                                         const std::vector<int>& wanted);

// Where each input/intermediate value lives in the activation arena. Values
// whose lifetimes (first write .. last read, in schedule order) do not overlap
// share bytes.
struct MemoryPlan {
    std::vector<int64_t> offset;  // per value; -1 for weights
    uint64_t arena_bytes = 0;     // size of the arena
    uint64_t total_bytes = 0;     // what one buffer per tensor would take
    uint64_t scratch_bytes = 0;   // GpuExecutor: the nodes' scratch (OpDef::scratch_bytes), one buffer for
                                  // all, a step's nodes side by side in it
};
// share = false gives every value bytes of its own (GpuExecutor's keep_all).
// With `step` (Graph::stepped_order's), lifetimes count in steps: values alive
// in one step never share bytes, as its nodes may run at once.
MemoryPlan plan_memory(const Graph& g, const std::vector<int>& order, uint64_t alignment, bool share = true,
                       const std::vector<int>& step = {});

// How a GpuExecutor orders the graph's nodes. Steps (the default) and Late:
// Graph::stepped_order's, early or late; within a step the nodes that ask for
// scratch come first (they write it and read it back: the barrier inside them
// then waits for them alone). Serial: topo_order, barriers wherever a node reads
// its predecessors' outputs. A profiled executor always runs Serial, so that each
// node's timestamps time it alone.
enum class Schedule { Steps, Late, Serial };
const char* schedule_name(Schedule s);

class GpuExecutor {
public:
    // Uploads the weights the graph uses, plans memory and records the graph.
    // keep_all (a debug mode, for `vtloc check`): every value gets bytes of its
    // own and the whole arena is read back after a run, so value() can return
    // any intermediate as the GPU computed it.
    GpuExecutor(rt::Context& ctx, const Graph& g, const WeightStore& weights, bool profile = false,
                bool keep_all = false);
    // The same, reading its weights from (and adding missing ones to) a
    // model's resident set, shared with the model's other executors.
    GpuExecutor(rt::Context& ctx, const Graph& g, const WeightStore& weights,
                std::shared_ptr<ResidentWeights> resident, bool profile = false, bool keep_all = false,
                Schedule schedule = Schedule::Steps);
    ~GpuExecutor();

    TensorMap run(const TensorMap& inputs);
    // After run() with keep_all: input or intermediate value `id` as on the GPU.
    HostTensor value(int id) const;

    const MemoryPlan& memory_plan() const { return plan_; }
    // Device bytes of the weights this graph reads (resident, maybe shared).
    uint64_t weight_bytes() const { return weight_bytes_; }
    const rt::Sequence& sequence() const { return *seq_; }
    std::vector<rt::Sequence::NodeTime> node_times() const { return seq_->node_times(); }

private:
    rt::BufferView view_of(int value) const;
    // Uploads missing weights, plans and allocates the arena, records the graph.
    void build(const WeightStore& weights, uint64_t align, bool keep_all, Schedule schedule);

    rt::Context& ctx_;
    Graph graph_;
    std::vector<int> order_, step_;  // the schedule's order, and each position's step
    MemoryPlan plan_;
    std::shared_ptr<ResidentWeights> resident_;
    size_t uploaded_ = ResidentWeights::kNone;  // the batch this build's ensure() added
    uint64_t weight_bytes_ = 0;
    rt::Buffer arena_;
    rt::Buffer scratch_;  // shared by the nodes that ask for scratch (OpDef::scratch_bytes)
    rt::Buffer staging_in_, staging_out_;
    rt::Buffer staging_all_;  // keep_all: a copy of the whole arena
    std::map<std::string, uint64_t> in_offsets_, out_offsets_;
    std::unique_ptr<rt::Sequence> seq_;
};

}  // namespace vtloc
