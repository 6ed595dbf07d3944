// Farthest-point sampling's workgroup sizes timed side by side at the paper's SA1
// and SA2 sizes: one workgroup runs all S sequential steps, so the size sets a
// step's latency (engine/ops/fps.cpp chooses it without timing).
#pragma once

#include <nlohmann/json.hpp>

#include "runtime/context.h"

namespace vtloc::bench {

// {rows}: a row {points, npoint, threads (0: the device's choice), workgroup, shader,
// ms (the node's GPU time, stats over reps)} for the default and for every power of
// two from the subgroup size to the device's limit (1024 at most); a size the device
// refuses has {refused: the reason}.
nlohmann::json fps_variants(rt::Context& ctx, int reps);

}  // namespace vtloc::bench
