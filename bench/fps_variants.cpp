#include "bench/fps_variants.h"

#include <cmath>
#include <memory>

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
        // All sizes built first, then timed in turns, one run each a round: on an
        // H200 a size timed alone after another ran at the clocks that one left (SA1's
        // sizes 4-6x slower than in the model, SA2's first two 6x slower than the rest).
        std::vector<std::unique_ptr<GpuExecutor>> execs(sizes.size());
        std::vector<std::vector<double>> ms(sizes.size());
        std::vector<json> row(sizes.size());
        for (size_t i = 0; i < sizes.size(); ++i) {
            row[i] = {{"points", N}, {"npoint", S}, {"threads", sizes[i]}};
            try {
                Graph g;
                const int x = g.input("x", {N, 3});
                g.output(ops::fps(g, x, S, "fps", false, false, sizes[i])[0], "index");
                execs[i] = std::make_unique<GpuExecutor>(ctx, g, WeightStore{}, /*profile=*/true);
                execs[i]->run(in);
                const auto& log = execs[i]->sequence().dispatch_log();
                row[i]["shader"] = log.back().shader;
                row[i]["workgroup"] = log.back().spec.empty() ? 0u : log.back().spec.at(0);
            } catch (const Error& e) {
                row[i]["refused"] = e.what();
            }
        }
        for (int r = 0; r < reps; ++r)
            for (size_t i = 0; i < sizes.size(); ++i) {
                if (!execs[i]) continue;
                execs[i]->run(in);
                for (const auto& t : execs[i]->node_times())
                    if (t.label == "fps") ms[i].push_back(t.ms);
            }
        for (size_t i = 0; i < sizes.size(); ++i) {
            if (execs[i]) row[i]["ms"] = stats_json(ms[i]);
            rows.push_back(row[i]);
        }
    }
    return {{"rows", rows}};
}

}  // namespace vtloc::bench
