#pragma once
// A device profile: the limits of a named GPU in a small JSON file, so that a
// machine without that GPU (lavapipe) can make the engine's choices for it and
// report them (`vtloc-bench --plan-for FILE`: workgroups per dispatch per node).
// `vtloc devices --save-profile FILE` writes one from a real device; shipped
// examples are in bench/device_profiles/. A Context made with
// ContextOptions::plan_for records dispatches as that device would, never runs
// them (docs/performance.md, "Planning for another GPU").
#include <string>

#include "runtime/context.h"

namespace vtloc::rt {

// Throws vtloc::Error naming the file and the field that is missing or wrong.
DeviceInfo read_device_profile(const std::string& path);
DeviceInfo parse_device_profile(const std::string& text, const std::string& source);
std::string device_profile_json(const DeviceInfo& d);

}  // namespace vtloc::rt
