#include "bench/flops.h"

namespace vtloc::bench {

std::map<std::string, double> node_flops(const Graph& g) {
    std::map<std::string, double> f;
    for (const Node& n : g.nodes()) {
        double flops = 0;
        if (n.op == "conv2d") {  // out [N, Cout, OH, OW]; the weight holds Cout * Cin * KH * KW in either layout
            const Shape& out = g.value(n.outputs[0]).shape;
            flops = 2.0 * double(out[0] * out[2] * out[3]) * double(numel(g.value(n.inputs[1]).shape));
        } else if (n.op == "linear") {  // weight [N, K] on rows [..., K]
            const Shape& x = g.value(n.inputs[0]).shape;
            flops = 2.0 * double(numel(x) / x.back()) * double(numel(g.value(n.inputs[1]).shape));
        } else if (n.op == "group_linear") {  // rows before the max; weight [K, N] (and W0 [K0, K])
            const int mode = int(n.params.get("in", 0));
            double w = double(numel(g.value(n.inputs[mode == 1 ? 3 : 1]).shape));
            const int hidden = int(n.params.get("hidden", 0));
            if (hidden == 1) w += double(numel(g.value(n.inputs[5]).shape));  // W0^T at 3, W^T at 5
            if (hidden == 2) w = double(numel(g.value(n.inputs[4]).shape));   // W^T (U counts in its own node)
            const double rows = mode == 1 ? double(numel(g.value(n.inputs[2]).shape))
                                          : double(g.value(n.inputs[0]).shape[mode == 0 ? 1 : 0]);
            flops = 2.0 * rows * w;
        } else {
            continue;
        }
        f[n.name] += flops;
    }
    return f;
}

}  // namespace vtloc::bench
