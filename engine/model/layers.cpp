#include "engine/model/layers.h"

#include "engine/ops/common.h"
#include "engine/ops/build.h"

namespace vtloc {

int add_linear(Graph& g, const WeightStore& w, const std::string& prefix, int x, uint32_t act, double slope) {
    const HostTensor& weight = w.get(prefix + ".weight");
    const int bias = w.has(prefix + ".bias") ? g.weight(prefix + ".bias", {weight.shape.at(0)}) : -1;
    return ops::linear(g, x, g.weight(prefix + ".weight", weight.shape), bias, ops::Act(act), slope, prefix);
}

int add_mlp(Graph& g, const WeightStore& w, const std::string& prefix, int x, int layers, uint32_t final_act) {
    for (int i = 0; i < layers; ++i)
        x = add_linear(g, w, prefix + "." + std::to_string(2 * i), x,
                       i + 1 < layers ? uint32_t(ops::kActRelu) : final_act);
    return x;
}

}  // namespace vtloc
