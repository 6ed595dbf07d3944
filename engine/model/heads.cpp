#include "engine/model/heads.h"

#include "base/error.h"
#include "engine/model/layers.h"
#include "engine/ops/common.h"
#include "engine/ops/build.h"

namespace vtloc {

namespace {

std::vector<int> ilu_inputs(Graph& g, const WeightStore& w, int ft, int fp, int iters, int max_iters) {
    if (max_iters < 0 || max_iters > limits::kMaxIters)
        throw Error("ILU iterations must be in 0.." + std::to_string(limits::kMaxIters) + ", got " +
                    std::to_string(max_iters));
    std::vector<int> in{ft, fp, iters};
    for (int v : ilu_weight_inputs(g, w)) in.push_back(v);
    return in;
}

}  // namespace

std::vector<int> ilu_weight_inputs(Graph& g, const WeightStore& w) {
    std::vector<int> in;
    for (const char* gate : {"convz", "convr", "convq"})
        for (const char* part : {".weight", ".bias"}) {
            std::string n = std::string("ilu.") + gate + part;
            in.push_back(g.weight(n, w.get(n).shape));
        }
    for (const char* n : {"ilu.head.0.weight", "ilu.head.0.bias", "ilu.head.2.weight", "ilu.head.2.bias"})
        in.push_back(g.weight(n, w.get(n).shape));
    return in;
}

IluOutputs build_ilu(Graph& g, const WeightStore& w, int ft, int fp, int iters, int max_iters) {
    std::vector<int> in = ilu_inputs(g, w, ft, fp, iters, max_iters);
    std::vector<int> out = ops::ilu(g, in, max_iters, "ilu");
    return {out[0], out[1]};
}

IluRetrieveOutputs build_ilu_retrieve(Graph& g, const WeightStore& w, int ft, int fp, int iters, int max_iters,
                                      int candidates, int cloud, int symmetry, int64_t k) {
    std::vector<int> in = ilu_inputs(g, w, ft, fp, iters, max_iters);
    std::vector<int> out = ops::ilu_retrieve(g, in, max_iters, candidates, cloud, symmetry, k, "ilu");
    return {{out[0], out[1]}, out[2], out[3], out[4]};
}

IluOutputs build_ilu_stepped(Graph& g, const WeightStore& w, int ft, int fp, int iters, int max_iters) {
    std::vector<int> in = ilu_inputs(g, w, ft, fp, iters, max_iters);
    if (max_iters < 1) throw Error("a stepped ILU needs max_iters >= 1");
    in.push_back(ft);  // step 0 reads no state; F^t fills the slot
    std::vector<int> out;
    for (int k = 0; k < max_iters; ++k) {
        out = ops::ilu_step(g, in, max_iters, k, "ilu.step" + std::to_string(k));
        in.back() = out[0];
    }
    return {out[1], out[2]};
}

HostTensor ilu_iters_input(int n, int max_iters) {
    if (n < 0 || n > max_iters)
        throw Error("ILU iterations must be in 0.." + std::to_string(max_iters) + ", got " + std::to_string(n));
    return HostTensor::from_ints({1}, {n});
}

int build_mcr(Graph& g, const WeightStore& w, const ModelConfig& config, int ft, int fp) {
    int fused = ops::concat(g, {ft, fp}, "mcr.fused");
    int layers = int(config.mcr_hidden.size()) + 1;
    return add_mlp(g, w, "mcr.decoder", fused, layers, ops::kActTanh);
}

}  // namespace vtloc
