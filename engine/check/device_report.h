#pragma once
// The device facts a check reports: name, driver (name, version and info where
// the driver reports them) and the limits that choose shader variants (workgroup
// sizes, subgroup size, shared memory, texel-buffer and storage-buffer ranges).
#include <string>
#include <utility>
#include <vector>

namespace vtloc::rt {
class Context;
}

namespace vtloc::check {

struct DeviceReport {
    std::string name, type, vulkan, driver;
    std::vector<std::pair<std::string, std::string>> limits;  // name, value
};

DeviceReport device_report(rt::Context& ctx);

}  // namespace vtloc::check
