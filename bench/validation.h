#pragma once
// Every bench ends with this: with VTLOC_VALIDATION=1 (the smoke tests) a
// validation message means the measured work was not valid Vulkan, so the run fails.
namespace vtloc::rt {
class Context;
}

namespace vtloc::bench {

// Prints each validation message the context collected as "<tool>: validation
// layer: ..." on stderr, then throws vtloc::Error if there was any.
void check_validation(rt::Context& ctx, const char* tool);

}  // namespace vtloc::bench
