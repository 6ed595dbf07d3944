#include "bench/flops.h"

#include <vector>

#include "engine/op.h"
#include "engine/ops/point_common.h"

namespace vtloc::bench {
namespace {

// Rows of `ball` [S, NS] that are not padding.
double real_rows(const HostTensor& ball) {
    double n = 0;
    for (int64_t m = 0; m < ball.size(); ++m) n += !ops::padding_row(ball, m, ball.shape.at(1));
    return n;
}

}  // namespace

std::map<std::string, HostTensor> ball_indices(const Graph& g, const WeightStore& w, const TensorMap& inputs) {
    std::vector<int> ids;
    std::vector<std::string> names;
    for (const Node& n : g.nodes())
        if (n.op == "ball_query") ids.push_back(n.outputs[0]), names.push_back(n.name);
    const std::map<int, HostTensor> vals = run_cpu_values(g, w, inputs, ids);
    std::map<std::string, HostTensor> balls;
    for (size_t k = 0; k < ids.size(); ++k) balls[names[k]] = vals.at(ids[k]);
    return balls;
}

std::map<std::string, double> node_flops(const Graph& g, const std::map<std::string, HostTensor>& balls) {
    const std::vector<int> producer = g.producers();
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
            const bool x_pm = n.params.get("x_point_major", 0) != 0;  // x [M, K] instead of [K, M]
            double rows = mode == 1 ? double(numel(g.value(n.inputs[2]).shape))
                                    : double(g.value(n.inputs[0]).shape[mode == 0 && !x_pm ? 1 : 0]);
            if (n.params.get("pad", 0) != 0) {  // the ball: input 2 (in = 1) or 3 (a max over rows)
                const int p = producer[size_t(n.inputs[mode == 1 ? 2 : 3])];
                auto it = p >= 0 ? balls.find(g.nodes()[size_t(p)].name) : balls.end();
                if (it != balls.end()) rows = real_rows(it->second);
            }
            flops = 2.0 * rows * w;
        } else {
            continue;
        }
        f[n.name] += flops;
    }
    return f;
}

}  // namespace vtloc::bench
