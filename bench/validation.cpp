#include "bench/validation.h"

#include <cstdio>
#include <string>

#include "base/error.h"
#include "runtime/context.h"

namespace vtloc::bench {

void check_validation(rt::Context& ctx, const char* tool) {
    const std::vector<rt::ValidationMessage> msgs = ctx.take_validation_messages();
    for (const auto& m : msgs) std::fprintf(stderr, "%s: validation layer: %s: %s\n", tool, m.severity.c_str(), m.text.c_str());
    if (!msgs.empty()) throw Error(std::to_string(msgs.size()) + " validation message(s); the numbers are not trusted");
}

}  // namespace vtloc::bench
