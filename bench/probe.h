#pragma once
// What every bench reports against: the device's own arithmetic peak (a
// probe shader of independent vec4 fma chains) and its per-dispatch overhead.
#include <algorithm>
#include <chrono>
#include <vector>

namespace vtloc::rt {
class Context;
}

namespace vtloc::bench {

struct Stats {
    double median = 0, p10 = 0, p90 = 0, min = 0, max = 0;
};
Stats summarize(std::vector<double> samples);
// Least-squares slope of y over x (0 when x does not vary).
double slope(const std::vector<double>& x, const std::vector<double>& y);

// Wall-clock milliseconds of f(), `reps` times after `warmup` untimed calls.
template <class F>
std::vector<double> time_ms(F&& f, int warmup, int reps) {
    for (int i = 0; i < warmup; ++i) f();
    std::vector<double> out;
    for (int i = 0; i < reps; ++i) {
        auto t0 = std::chrono::steady_clock::now();
        f();
        out.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    return out;
}

// Median GFLOP/s of the peak probe; the dispatch is grown until one run takes >= 50 ms.
double peak_gflops(rt::Context& ctx, int reps = 5);
// Median microseconds one empty dispatch adds to a command buffer.
double dispatch_overhead_us(rt::Context& ctx, int reps = 5);

}  // namespace vtloc::bench
