#pragma once
// SplitMix64: exact 64-bit integer arithmetic, so a seed gives the same
// numbers on every platform and standard library (std::*_distribution
// outputs differ between libraries). Same generator and uniform() as
// weights_tools/synthetic.py, so Python can reproduce any draw.
#include <cstdint>

namespace vtloc::io {

class SplitMix64 {
public:
    explicit SplitMix64(uint64_t seed) : state_(seed) {}

    uint64_t next_u64() {
        state_ += 0x9E3779B97F4A7C15ull;
        uint64_t z = state_;
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }

    // Uniform in [0, 1) from the top 53 bits: exactly representable, no rounding.
    double uniform() { return double(next_u64() >> 11) * 0x1.0p-53; }

private:
    uint64_t state_;
};

}  // namespace vtloc::io
