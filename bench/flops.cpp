#include "bench/flops.h"

#include <set>
#include <vector>

#include "base/error.h"
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

// The node that writes each value (-1: an input or weight).
std::vector<int> producers(const Graph& g) {
    std::vector<int> producer(g.values().size(), -1);
    for (size_t i = 0; i < g.nodes().size(); ++i)
        for (int id : g.nodes()[i].outputs) producer[size_t(id)] = int(i);
    return producer;
}

}  // namespace

std::map<std::string, HostTensor> ball_indices(const Graph& g, const WeightStore& w, const TensorMap& inputs) {
    const std::vector<int> producer = producers(g);
    std::set<int> need;  // the ball_query nodes and every node they depend on
    std::vector<int> todo;
    for (size_t i = 0; i < g.nodes().size(); ++i)
        if (g.nodes()[i].op == "ball_query") todo.push_back(int(i));
    while (!todo.empty()) {
        const int n = todo.back();
        todo.pop_back();
        if (!need.insert(n).second) continue;
        for (int id : g.nodes()[size_t(n)].inputs)
            if (producer[size_t(id)] >= 0) todo.push_back(producer[size_t(id)]);
    }
    std::vector<HostTensor> vals(g.values().size());
    std::vector<const HostTensor*> ptr(g.values().size(), nullptr);
    for (size_t i = 0; i < g.values().size(); ++i) {
        const Value& v = g.values()[i];
        if (v.kind == ValueKind::Input && inputs.count(v.name)) ptr[i] = &inputs.at(v.name);
    }
    std::map<std::string, HostTensor> balls;
    for (int ni : g.topo_order()) {
        if (!need.count(ni)) continue;
        const Node& n = g.nodes()[size_t(ni)];
        std::vector<const HostTensor*> in;
        std::vector<HostTensor*> out;
        for (int id : n.inputs) {
            const Value& v = g.value(id);
            if (!ptr[size_t(id)] && v.kind == ValueKind::Weight) ptr[size_t(id)] = &w.get(v.name, v.shape);
            if (!ptr[size_t(id)]) throw Error("ball_indices: node '" + n.name + "' needs input '" + v.name + "', not given");
            in.push_back(ptr[size_t(id)]);
        }
        for (int id : n.outputs) {
            vals[size_t(id)] = HostTensor(g.value(id).shape, g.value(id).type);
            ptr[size_t(id)] = &vals[size_t(id)];
            out.push_back(&vals[size_t(id)]);
        }
        find_op(n.op).cpu(in, out, n.params);
        if (n.op == "ball_query") balls[n.name] = vals[size_t(n.outputs[0])];
    }
    return balls;
}

std::map<std::string, double> node_flops(const Graph& g, const std::map<std::string, HostTensor>& balls) {
    const std::vector<int> producer = producers(g);
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
            double rows = mode == 1 ? double(numel(g.value(n.inputs[2]).shape))
                                    : double(g.value(n.inputs[0]).shape[mode == 0 ? 1 : 0]);
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
