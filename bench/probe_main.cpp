// Prints the device's fma peak and per-dispatch overhead (medians over repeats).
#include <cstdio>

#include "bench/probe.h"
#include "bench/validation.h"
#include "base/error.h"
#include "runtime/context.h"

int main() {
    try {
        vtloc::rt::Context ctx;
        std::printf("device: %s\n", ctx.info().name.c_str());
        std::printf("peak probe: %.1f GFLOP/s (vec4 fma chains, median of 5)\n", vtloc::bench::peak_gflops(ctx));
        std::printf("empty dispatch: %.2f us each (median of 5 runs of 1000)\n",
                    vtloc::bench::dispatch_overhead_us(ctx));
        vtloc::bench::check_validation(ctx, "vtloc-bench-probe");
    } catch (const vtloc::Error& e) {
        std::fprintf(stderr, "vtloc-bench-probe: %s\n", e.what());
        return 1;
    }
    return 0;
}
