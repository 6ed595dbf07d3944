// The touches file reader (vtloc sequence, vtloc demo) on arbitrary text, and
// the relative motions it forms: every input either parses into checked
// rigid motions or throws vtloc::Error.
#include <cmath>
#include <cstdlib>
#include <string_view>

#include "base/error.h"
#include "engine/io/touch_sequence.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    try {
        const vtloc::io::TouchSequence s =
            vtloc::io::parse_touch_sequence(std::string_view(reinterpret_cast<const char*>(data), size), "/fuzz", "fuzz");
        for (const auto& m : s.relative_motions("fuzz"))
            if (m)
                for (double v : m->R)
                    if (!std::isfinite(v)) std::abort();  // the reader promised checked motions
    } catch (const vtloc::Error&) {
    }
    return 0;
}
