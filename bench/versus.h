#pragma once
// What vtloc-bench adds around the engine's numbers: the host CPU (lavapipe's
// speed depends on it) and the PyTorch reference timed on the same inputs in
// the same run (--vs-pytorch), with engine/PyTorch ratios.
#include <nlohmann/json.hpp>
#include <string>

#include "engine/tensor.h"

namespace vtloc::bench {

// {"cpu": model name, "cores": n, "simd": [avx, avx2, fma, avx512f, ...]} from /proc/cpuinfo.
nlohmann::json host_cpu();

struct TorchRun {
    std::string python;      // interpreter with torch
    std::string repo;        // folder holding weights_tools/
    std::string weights, image;
    HostTensor cloud;        // [N, 6]: the engine's cloud, written as PLY for the reference
    int reps = 20, warmup = 3;
    std::string device = "cpu";  // bench_torch --device: cpu or cuda
};

// Runs python -m weights_tools.bench_torch; its JSON report. Throws vtloc::Error on failure.
nlohmann::json run_pytorch(const TorchRun& t);

// engine time / PyTorch time per matching measurement (below 1: the engine is faster).
nlohmann::json engine_over_pytorch(const nlohmann::json& engine, const nlohmann::json& torch);

}  // namespace vtloc::bench
