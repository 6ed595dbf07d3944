#pragma once
// vtloc-bench's gel stage (SPEC 9, #43's speed goals): the gel's shape from one frame (the
// GPU pipeline: gradient, mask, solve, with its uploads and read-back; and the CPU reference),
// and render-and-compare on an object: its codebook rendered once, one touch scored against it.
#include <nlohmann/json.hpp>
#include <string>

namespace vtloc {
namespace rt {
class Context;
}
namespace bench {

struct GelBenchOptions {
    std::string object;  // a mesh for the codebook (default: the potato tour's object)
    int reps = 5;
};

// JSON: frame, size [W, H], shape_ms (GPU) and shape_cpu_ms (stats), shape_nodes_ms {node: stats}
// (GPU timestamps of a profiled run), solves and rendered (this frame, and a rendered one under
// the rendered frames' mask: {from_zeros, coarse_start} x {shape_ms, solve_gpu_ms, mask_pixels,
// ...}, and uses: the solve the frame's reader takes), codebook {object,
// hypotheses, render_ms (once), score_ms (stats)}. ctx null: the CPU reference only.
nlohmann::json measure_gel(rt::Context* ctx, const GelBenchOptions& o);

}  // namespace bench
}  // namespace vtloc
