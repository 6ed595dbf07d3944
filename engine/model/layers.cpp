#include "engine/model/layers.h"

#include "engine/ops/common.h"

namespace vtloc {

int add_linear(Graph& g, const WeightStore& w, const std::string& prefix, int x, uint32_t act, double slope) {
    const HostTensor& weight = w.get(prefix + ".weight");
    std::vector<int> in{x, g.weight(prefix + ".weight", weight.shape)};
    if (w.has(prefix + ".bias")) in.push_back(g.weight(prefix + ".bias", {weight.shape.at(0)}));
    return g.add1("linear", in, {{"act", double(act)}, {"slope", slope}}, prefix);
}

int add_mlp(Graph& g, const WeightStore& w, const std::string& prefix, int x, int layers, uint32_t final_act) {
    for (int i = 0; i < layers; ++i)
        x = add_linear(g, w, prefix + "." + std::to_string(2 * i), x,
                       i + 1 < layers ? uint32_t(ops::kActRelu) : final_act);
    return x;
}

}  // namespace vtloc
