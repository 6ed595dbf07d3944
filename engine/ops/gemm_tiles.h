#pragma once
// Tile sizes for shaders/gemm.comp, chosen per device and problem shape.
#include <cstdint>

#include "runtime/context.h"

namespace vtloc::ops {

struct GemmTiles {
    uint32_t bm, bn, bk, tm, tn;
    uint32_t threads() const { return (bm / tm) * (bn / tn); }
    uint32_t shared_bytes() const { return (bm + bn) * bk * 4; }
};

// The largest tile the device can run (invocations, workgroup size, shared
// memory), preferring thread counts that are whole subgroups, and a short-M
// tile when M is small (a single vector times a matrix).
GemmTiles choose_gemm_tiles(const rt::DeviceInfo& d, int64_t M, int64_t N);

}  // namespace vtloc::ops
