#pragma once
// A grid cell's integer indices packed into one hash key, 21 bits an axis. Masked, so no index
// overflows it (negative ones included); cells 2^21 apart along an axis share a key, so a grid
// must stay narrower than that or its caller compare the points a key finds.
#include <cstdint>

namespace vtloc {

inline int64_t cell_key(int64_t x, int64_t y, int64_t z) {
    return ((x & 0x1FFFFF) << 42) | ((y & 0x1FFFFF) << 21) | (z & 0x1FFFFF);
}

}  // namespace vtloc
