#pragma once
// TEST-ONLY fault injection for the model check (engine/check/graph_check.h):
// corrupts what the GPU computed for one node before it is compared, as a
// driver that miscompiles that node's shader would. Declared only here (an
// internal header the tests include); neither the public API nor the CLI can
// reach it. Per thread, so concurrent checks on other threads are unaffected.
#include <functional>
#include <string>

#include "engine/tensor.h"

namespace vtloc::check::testing {

// corrupt(output) is called on the named node's first output (as read back
// from the GPU) in every check_graph on this thread, until cleared. One fault
// per name (a second call for a name replaces it); several names may be set.
void set_fault(const std::string& node, std::function<void(HostTensor&)> corrupt);
void clear_fault();  // all of them
// Applies the fault set for `name`, if any, to t: for values a check compares
// outside check_graph ("codebook.heights": check_tracker's codebook rows).
void apply_fault(const std::string& name, HostTensor& t);

}  // namespace vtloc::check::testing
