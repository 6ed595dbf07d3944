#include "bench/ilu_variants.h"

#include <algorithm>

#include "base/error.h"
#include "bench/model_bench.h"
#include "engine/executor.h"
#include "engine/model/heads.h"
#include "engine/ops/build.h"

namespace vtloc::bench {

using nlohmann::json;

namespace {

std::vector<int> inputs(Graph& g, const WeightStore& w, int64_t C) {
    std::vector<int> in{g.input("ft", {1, C}), g.input("fp", {1, C}), g.input("iters", {1}, ElemType::I32)};
    for (int v : ilu_weight_inputs(g, w)) in.push_back(v);
    return in;
}

HostTensor ramp(int64_t C, float scale) {
    HostTensor t({1, C});
    for (int64_t i = 0; i < C; ++i) t.data[size_t(i)] = scale * float((i * 37) % 97) / 97.0f - 0.5f * scale;
    return t;
}

}  // namespace

json ilu_variants(rt::Context& ctx, const WeightStore& w, int iters, int reps) {
    const int64_t C = w.get("ilu.convz.bias").shape.at(0);
    const TensorMap in{{"ft", ramp(C, 2.0f)}, {"fp", ramp(C, 1.0f)}, {"iters", ilu_iters_input(iters, iters)}};
    const rt::DeviceInfo& d = ctx.info();
    const uint32_t most = std::min({d.max_invocations, d.max_workgroup_size[0], 256u});
    std::vector<int> waves{0, 1};
    for (uint32_t L = std::max(1u, d.subgroup_size); L <= most; L *= 2) waves.push_back(int(L));
    json rows = json::array();
    for (int wave : waves) {
        json row{{"wave", wave}};
        try {
            Graph g;
            std::vector<int> out = ops::ilu(g, inputs(g, w, C), iters, "ilu", 0, true, wave);
            g.output(out[1], "contact");
            GpuExecutor exec(ctx, g, w, /*profile=*/true);
            time_node(exec, in, "ilu", reps, row);
        } catch (const Error& e) {
            row["refused"] = e.what();
        }
        rows.push_back(row);
    }
    return {{"C", C}, {"iters", iters}, {"rows", rows}};
}

}  // namespace vtloc::bench
