// The fused ILU node's shader variants timed side by side on the model's sizes:
// which one a device should take (engine/ops/ilu_math.cpp chooses without timing).
#pragma once

#include <nlohmann/json.hpp>

#include "engine/weights.h"
#include "runtime/context.h"

namespace vtloc::bench {

// {C, iters, rows}: a row {wave, shader, workgroup, ms (the node's GPU time at `iters`,
// stats over reps)} for the default (wave 1: the shader it picks), the shared-memory
// shader (wave 0) and the register-resident one at the subgroup size and its doublings
// up to 256 invocations or the device's limit; a variant the device refuses has
// {wave, refused: the reason}. (512 and 1024 ran 5-20x slower on an H200 and lavapipe.)
nlohmann::json ilu_variants(rt::Context& ctx, const WeightStore& w, int iters, int reps);

}  // namespace vtloc::bench
