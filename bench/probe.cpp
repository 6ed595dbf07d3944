#include "bench/probe.h"

#include "engine/ops/common.h"
#include "runtime/context.h"
#include "runtime/memory.h"
#include "runtime/sequence.h"

namespace vtloc::bench {

double slope(const std::vector<double>& x, const std::vector<double>& y) {
    const double n = double(x.size());
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (size_t i = 0; i < x.size(); ++i) sx += x[i], sy += y[i], sxx += x[i] * x[i], sxy += x[i] * y[i];
    const double d = n * sxx - sx * sx;
    return d != 0 ? (n * sxy - sx * sy) / d : 0.0;
}

Stats summarize(std::vector<double> s) {
    Stats st;
    if (s.empty()) return st;
    std::sort(s.begin(), s.end());
    auto at = [&](double q) { return s[size_t(q * double(s.size() - 1) + 0.5)]; };
    st.median = s.size() % 2 ? s[s.size() / 2] : 0.5 * (s[s.size() / 2 - 1] + s[s.size() / 2]);
    st.p10 = at(0.1);
    st.p90 = at(0.9);
    st.min = s.front();
    st.max = s.back();
    return st;
}

double peak_gflops(rt::Context& ctx, int reps) {
    const uint32_t iters = 512;
    uint32_t local = ops::elementwise_local_size(ctx.info());
    const rt::Pipeline& pipe = ops::pipeline(ctx, "peak_fma", 1, 4, {local, iters});
    uint32_t groups = 16;
    while (true) {
        rt::Buffer out(ctx, uint64_t(groups) * local * 16, rt::MemoryKind::Device);
        rt::Sequence seq(ctx);
        seq.begin();
        float seed = 1.0f;
        seq.dispatch(pipe, {{{out.handle(), 0, out.size()}, rt::Access::Write}}, &seed, 4, groups);
        seq.end();
        Stats st = summarize(time_ms([&] { seq.submit_and_wait(); }, 1, reps));
        double flops = double(groups) * local * iters * 8 * 4 * 2;
        if (st.median >= 50.0 || groups >= ctx.info().max_workgroup_count[0] / 2 || groups >= (1u << 20))
            return flops / (st.median * 1e-3) * 1e-9;
        groups *= st.median > 1.0 ? std::max(2u, uint32_t(60.0 / st.median)) : 8u;
        groups = std::min(groups, std::min(ctx.info().max_workgroup_count[0], 1u << 20));
    }
}

double dispatch_overhead_us(rt::Context& ctx, int reps) {
    const rt::Pipeline& pipe = ops::pipeline(ctx, "empty", 1, 0, {ops::elementwise_local_size(ctx.info())});
    rt::Buffer buf(ctx, 256, rt::MemoryKind::Device);
    auto median_ms = [&](int dispatches) {
        rt::Sequence seq(ctx);
        seq.begin();
        // Marked as a read so the tracker inserts no barriers between them.
        for (int i = 0; i < dispatches; ++i)
            seq.dispatch(pipe, {{{buf.handle(), 0, 256}, rt::Access::Read}}, nullptr, 0, 1);
        seq.end();
        return summarize(time_ms([&] { seq.submit_and_wait(); }, 1, reps)).median;
    };
    const int n = 1000;
    return (median_ms(n) - median_ms(1)) / (n - 1) * 1e3;
}

}  // namespace vtloc::bench
