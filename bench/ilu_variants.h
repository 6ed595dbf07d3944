// The fused ILU node's shader variants timed side by side on the model's sizes:
// which one a device should take (engine/ops/ilu_math.cpp chooses without timing).
#pragma once

#include <nlohmann/json.hpp>

#include "engine/weights.h"
#include "runtime/context.h"

namespace vtloc::bench {

// Rows {variant, workgroup, ms (median GPU time of the node at `iters`), chosen}:
// the shared-memory shader (wave 0) and the register-resident one at the subgroup
// size and its doublings up to the device's workgroup limit; "chosen" marks what
// the default (wave 1) runs. A variant the device refuses is listed with its reason.
nlohmann::json ilu_variants(rt::Context& ctx, const WeightStore& w, int iters, int reps);

}  // namespace vtloc::bench
