#pragma once
// vtloc-bench --plan-for PROFILE: the model's dispatches as a named GPU would get
// them (runtime/device_profile.h), recorded on a plan-only context, never run:
// workgroups per dispatch per node against the profile's compute units.
#include <nlohmann/json.hpp>

#include "engine/model/vtloc_runner.h"
#include "runtime/context.h"

namespace vtloc::bench {

// ctx: a plan-only context. One touch, object branch included (localize_once's graph).
nlohmann::json plan_model(rt::Context& ctx, const WeightStore& weights, const ModelConfig& cfg, const HostTensor& image,
                          const HostTensor& cloud);
void print_plan(const nlohmann::json& plan, FILE* f);

}  // namespace vtloc::bench
