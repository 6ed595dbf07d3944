#pragma once
// Wall-clock milliseconds for the benches' timed loops.
#include <chrono>

namespace vtloc::bench {

inline double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace vtloc::bench
