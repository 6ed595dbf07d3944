#pragma once
// Workgroup size for shaders with one invocation per output row (max_pool2d):
// there are only hundreds to thousands of rows, so a full
// 256-wide group would leave CPU devices' threads (one workgroup each) idle.
#include <algorithm>
#include <cstdint>

#include "engine/ops/common.h"

namespace vtloc::ops {

// The elementwise size, halved (in whole subgroups) until there are >= 16 groups.
inline uint32_t row_local_size(const rt::DeviceInfo& d, uint64_t rows) {
    const uint32_t sg = std::max(1u, d.subgroup_size);
    uint32_t local = elementwise_local_size(d);
    while (local > sg && rows < 16ull * local) local = std::max(sg, local / 2 / sg * sg);
    return local;
}

}  // namespace vtloc::ops
