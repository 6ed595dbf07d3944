#pragma once
// The whole-model measurements of vtloc-bench on one backend (a VtlocRunner
// on the GPU or on the CPU references), as JSON (schema: bench/README.md).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/probe.h"
#include "engine/model/vtloc_runner.h"

namespace vtloc::bench {

struct ModelBenchOptions {
    int reps = 20;          // timed repetitions per measurement
    int warmup = 3;         // untimed runs before them
    int profile_reps = 5;   // profiled runs (per node and per stage times)
    std::vector<int> iters{0, 4, 8, 16, 32, 64};  // ILU N sweep
    std::vector<int> batches{1, 4, 16};
    std::vector<int64_t> points{1024, 4096, 16384};  // point-branch scaling
    int stepped_iters = 16;  // N of the one-dispatch-per-iteration ILU recording (0: skip)
};

struct ModelBenchInputs {
    HostTensor image;     // I32 [H, W, 3]
    HostTensor cloud;     // [N, 6] object units, the model's point count
    std::string object;   // where `cloud` came from, sampled again for the point sweep
    double probe_gflops = 0;  // the device's fma peak (0 on the CPU)
};

nlohmann::json stats_json(const std::vector<double>& samples_ms);
// Node `label` of a profiled executor over `reps` runs after one untimed run (shader
// compilation): row["ms"], its GPU times' stats, and row["shader"], row["workgroup"],
// those of the last dispatch recorded.
void time_node(GpuExecutor& exec, const TensorMap& in, const std::string& label, int reps, nlohmann::json& row);

// An efficiency entry's fractions of the probe (fraction_of_peak, and
// fraction_of_peak_fastest), null without a probe; measure_model sets them with the
// probe taken before, vtloc-bench again with the higher of before and after.
void set_fractions_of_peak(nlohmann::json& efficiency, double probe_gflops);

// Everything on one backend: end to end, per stage, per node, the ILU sweep and
// per-iteration times, cached touches, batches, memory and the point sweep.
nlohmann::json measure_model(VtlocRunner& runner, const ModelBenchInputs& in, const ModelBenchOptions& opt);

}  // namespace vtloc::bench
