#include "bench/fps_variants.h"

#include <cmath>

#include "base/error.h"
#include "bench/model_bench.h"
#include "engine/executor.h"
#include "engine/ops/build.h"

namespace vtloc::bench {

using nlohmann::json;

namespace {

// N points spread over a unit sphere (a golden-angle spiral): distinct distances,
// as an object's surface gives.
HostTensor sphere(int64_t N) {
    HostTensor t({N, 3});
    for (int64_t i = 0; i < N; ++i) {
        const double z = 1.0 - 2.0 * (double(i) + 0.5) / double(N), r = std::sqrt(1.0 - z * z);
        const double a = 2.399963229728653 * double(i);
        t.data[size_t(3 * i)] = float(r * std::cos(a));
        t.data[size_t(3 * i + 1)] = float(r * std::sin(a));
        t.data[size_t(3 * i + 2)] = float(z);
    }
    return t;
}

}  // namespace

json fps_variants(rt::Context& ctx, int reps) {
    const rt::DeviceInfo& d = ctx.info();
    json rows = json::array();
    for (auto [N, S] : {std::pair<int64_t, int64_t>{1024, 512}, {512, 128}}) {
        const TensorMap in{{"x", sphere(N)}};
        std::vector<int64_t> sizes{0};
        for (uint32_t L = std::max(1u, d.subgroup_size); L <= std::min(1024u, d.max_invocations); L *= 2)
            sizes.push_back(L);
        for (int64_t threads : sizes) {
            json row{{"points", N}, {"npoint", S}, {"threads", threads}};
            try {
                Graph g;
                const int x = g.input("x", {N, 3});
                g.output(ops::fps(g, x, S, "fps", false, false, threads)[0], "index");
                GpuExecutor exec(ctx, g, WeightStore{}, /*profile=*/true);
                time_node(exec, in, "fps", reps, row);
            } catch (const Error& e) {
                row["refused"] = e.what();
            }
            rows.push_back(row);
        }
    }
    return {{"rows", rows}};
}

}  // namespace vtloc::bench
