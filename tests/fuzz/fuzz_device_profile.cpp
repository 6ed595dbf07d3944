// The device profile reader (`vtloc-bench --plan-for`, `vtloc devices --save-profile`) on
// arbitrary text. What it accepts must survive a write and a second read unchanged: the
// writer and the reader agree on every field.
#include <cstdlib>
#include <string>

#include "base/error.h"
#include "runtime/device_profile.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    vtloc::rt::DeviceInfo d;
    try {
        d = vtloc::rt::parse_device_profile(text, "fuzz");
    } catch (const vtloc::Error&) {
        return 0;
    }
    const std::string once = vtloc::rt::device_profile_json(d);
    const std::string twice = vtloc::rt::device_profile_json(vtloc::rt::parse_device_profile(once, "fuzz (written)"));
    if (once != twice) std::abort();
    return 0;
}
