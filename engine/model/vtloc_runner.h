#pragma once
// Runs VTLoc on the GPU (or on the CPU references): normalises the object,
// feeds the graphs of engine/model/vtloc_graph.h, and keeps one recorded
// executor per graph shape, so repeated calls only upload inputs and submit.
// Not thread-safe: use one runner per thread (each on its own rt::Context).
#include <array>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/executor.h"
#include "engine/ops/object_frame.h"
#include "engine/model/prepared_weights.h"
#include "engine/model/vtloc_graph.h"
#include "engine/weights.h"

namespace vtloc {

namespace rt {
class Context;
}

struct Symmetry {
    std::array<double, 3> axis_point{0, 0, 0};  // object units
    std::array<double, 3> axis_dir{0, 0, 1};
    int order = 1;
};

struct TouchOptions {
    int iters = -1;      // ILU iterations 0..64; -1: the config's
    int64_t k = 0;       // top-K size; 0: the config's K
    bool gma = true;     // compute the GMA alignment score
    std::optional<Symmetry> symmetry;
};

// An object ready for touches: its frame, normalised clouds, candidates and
// (once encoded) F^p.
struct EncodedObject {
    ObjectFrame frame;
    HostTensor cloud;       // network input, normalised, [N, 6] or [N, 3]
    HostTensor target;      // normalised [N, 6] (GMA's Chamfer target, heat-map points)
    HostTensor candidates;  // normalised [M, 3]
    HostTensor feature;     // F^p [1, C]
    TensorMap indices;      // point.sa*.fps / point.sa*.ball.* of the encoding run
};

struct TouchResult {
    TensorMap tensors;                     // SPEC section 8 names (ilu.c trimmed to N rows)
    std::array<double, 3> contact{};       // c^p in object units
    std::array<double, 3> contact_normalised{};
    std::vector<int32_t> topk_index;
    std::vector<float> topk_score;
    std::vector<float> heatmap;            // over the object cloud's points
    std::optional<float> alignment;        // chamfer(P^d, P) when GMA ran
};

class VtlocRunner {
public:
    // gpu == nullptr runs the CPU reference implementations. config: the
    // weights' own, already parsed (load_model_file's), so a load parses it once;
    // prepared weights (load_model_file's too) are not prepared again.
    VtlocRunner(PreparedWeights weights, ModelConfig config, rt::Context* gpu);
    VtlocRunner(const WeightStore& weights, ModelConfig config, rt::Context* gpu);
    // For weights alone (tests, benches): parses their config here, once.
    VtlocRunner(const WeightStore& weights, rt::Context* gpu);
    ~VtlocRunner();

    const ModelConfig& config() const { return config_; }
    const WeightStore& weights() const { return weights_; }
    bool on_gpu() const { return gpu_ != nullptr; }

    // cloud: [N, 6] object units (xyz, unit normals); candidates: [M, 3] object
    // units, or none for the cloud's own points. Runs the point branch once.
    EncodedObject encode_object(const HostTensor& cloud, const HostTensor* candidates = nullptr);

    // Touches on an encoded object: tactile branch + heads + retrieval, all the
    // images (same size) in one submit. images: I32 [H, W, 3] byte values.
    std::vector<TouchResult> localize(const EncodedObject& object, const std::vector<HostTensor>& images,
                                      const TouchOptions& options = {});

    // One touch, everything (object branch included) in one graph and one submit.
    TouchResult localize_once(const HostTensor& image, const HostTensor& cloud, const HostTensor* candidates,
                              const TouchOptions& options = {});

    // localize_once's graph and inputs, built but not run (`vtloc check`
    // cross-checks it node by node; run it with weights()).
    struct Prepared {
        Graph graph;
        TensorMap inputs;
    };
    Prepared prepare_once(const HostTensor& image, const HostTensor& cloud, const HostTensor* candidates,
                          const TouchOptions& options = {});

    // Time per node of the last run, in schedule order: GPU timestamps, or the
    // wall time of each CPU reference node on the CPU backend. Empty without
    // profiling (or where the GPU queue has no timestamps).
    void set_profiling(bool on) { profile_ = on; }
    std::vector<std::pair<std::string, double>> last_node_times() const;

    // Bench diagnostics: record the ILU head one dispatch per iteration
    // (engine/model/heads.h build_ilu_stepped), so profiling times each iteration.
    void set_ilu_stepped(bool on) { ilu_stepped_ = on; }
    // Bench diagnostics: retrieval in a dispatch of its own rather than as the
    // ILU's epilogue (engine/ops/ilu_retrieve.cpp), to time it apart.
    void set_retrieval_apart(bool on) { retrieval_apart_ = on; }
    // Bench diagnostics: how the GPU orders each graph's nodes (engine/executor.h
    // Schedule; Steps by default), to time the orders side by side.
    void set_schedule(Schedule s) { schedule_ = s; }
    // Pipeline barriers in the last run's recording (0 on the CPU).
    uint32_t last_barriers() const;

    // The graph of the last run, and on the GPU the device memory it holds.
    struct MemoryUse {
        uint64_t weight_bytes = 0;  // weights this graph reads
        uint64_t resident_weight_bytes = 0;  // every weight resident for this runner: each once, all shapes
        uint64_t arena_bytes = 0;   // activation arena (lifetime-planned peak) and the nodes' scratch
        uint64_t unplanned_bytes = 0;  // what one buffer per activation would take
    };
    const Graph* last_graph() const;
    MemoryUse last_memory() const;
    // The shaders the last run's recording dispatches, in order (empty on the CPU).
    std::vector<std::string> last_dispatch_shaders() const;
    // The workgroups of each of the last run's dispatches (gx * gy * gz), by node label, in order
    // (how well a dispatch can fill a GPU's compute units; empty on the CPU).
    std::vector<std::pair<std::string, uint64_t>> last_dispatch_workgroups() const;
    // Every graph shape this runner has built on the GPU so far.
    struct AllMemory {
        size_t graphs = 0;
        uint64_t resident_weight_bytes = 0;    // held: each weight once
        uint64_t weight_bytes_by_graph = 0;    // what one weight copy per graph would hold
        uint64_t arena_bytes = 0;              // the graphs' activation arenas together
    };
    AllMemory all_memory() const;

private:
    EncodedObject prepare_object(const HostTensor& cloud, const HostTensor* candidates) const;
    TensorMap run(const VtlocGraphSpec& spec, const TensorMap& inputs);
    TensorMap run_graph(const std::string& key, const std::function<Graph()>& build, const TensorMap& inputs);

    const PreparedWeights weights_;  // what every graph shape reads, never changed
    ModelConfig config_;  // the weights' config, parsed once per load
    rt::Context* gpu_;
    bool profile_ = false;
    bool ilu_stepped_ = false;
    bool retrieval_apart_ = false;
    Schedule schedule_ = Schedule::Steps;
    struct Compiled;
    // Weights on the GPU, once for every graph shape (made at the first GPU run).
    std::shared_ptr<ResidentWeights> resident_;
    std::map<std::string, std::unique_ptr<Compiled>> compiled_;
    Compiled* last_ = nullptr;
};

}  // namespace vtloc
