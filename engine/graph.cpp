#include "engine/graph.h"

#include <algorithm>

#include "base/error.h"
#include "engine/op.h"

namespace vtloc {

namespace {

// Per node, how many of its inputs other nodes write (missing) and which nodes read
// its outputs (consumers): Kahn's algorithm's start.
void dependencies(const std::vector<Node>& nodes, const std::vector<int>& producer, std::vector<int>& missing,
                  std::vector<std::vector<int>>& consumers) {
    missing.assign(nodes.size(), 0);
    consumers.assign(nodes.size(), {});
    for (size_t i = 0; i < nodes.size(); ++i)
        for (int in : nodes[i].inputs)
            if (int p = producer[size_t(in)]; p >= 0) {
                ++missing[i];
                consumers[size_t(p)].push_back(int(i));
            }
}

}  // namespace

int Graph::new_value(const std::string& name, Shape shape, ValueKind kind, ElemType type) {
    for (int64_t d : shape)
        if (d < 0) throw Error("value '" + name + "' has a negative dimension " + shape_str(shape));
    values_.push_back({name, std::move(shape), kind, type});
    return int(values_.size() - 1);
}

int Graph::input(const std::string& name, Shape shape, ElemType type) {
    for (const Value& v : values_)
        if (v.kind == ValueKind::Input && v.name == name) throw Error("duplicate graph input '" + name + "'");
    return new_value(name, std::move(shape), ValueKind::Input, type);
}

int Graph::weight(const std::string& name, Shape shape, ElemType type) {
    for (size_t i = 0; i < values_.size(); ++i)
        if (values_[i].kind == ValueKind::Weight && values_[i].name == name) {
            if (values_[i].shape != shape)
                throw Error("weight '" + name + "' used with shapes " + shape_str(values_[i].shape) +
                            " and " + shape_str(shape));
            return int(i);
        }
    return new_value(name, std::move(shape), ValueKind::Weight, type);
}

std::vector<int> Graph::add(const std::string& op, const std::vector<int>& inputs, Params params,
                            const std::string& name) {
    const OpDef& def = find_op(op);
    std::string label = name.empty() ? op + "_" + std::to_string(nodes_.size()) : name;
    for (const std::string& k : params.keys())
        if (std::find(def.params.begin(), def.params.end(), k) == def.params.end()) {
            std::string known;
            for (std::string_view n : def.params) known.append(known.empty() ? "" : ", ").append(n);
            throw Error("node '" + label + "' (" + op + "): unknown parameter '" + k + "' (" +
                        (known.empty() ? std::string("it takes none") : "it takes " + known) + ")");
        }
    std::vector<TensorDesc> in_descs;
    for (int id : inputs) {
        if (id < 0 || size_t(id) >= values_.size())
            throw Error("node '" + label + "': input value " + std::to_string(id) + " does not exist");
        in_descs.push_back({values_[size_t(id)].shape, values_[size_t(id)].type});
    }
    std::vector<TensorDesc> out_descs;
    try {
        out_descs = def.infer(in_descs, params);
    } catch (const Error& e) {
        throw Error("node '" + label + "' (" + op + "): " + e.what());
    }
    Node n{op, label, inputs, {}, std::move(params)};
    for (size_t i = 0; i < out_descs.size(); ++i) {
        // Appended piecewise: `":" + std::to_string(i)` trips GCC 12's -Wrestrict false positive.
        std::string name = label;
        if (out_descs.size() > 1) name.append(":").append(std::to_string(i));
        n.outputs.push_back(new_value(name, out_descs[i].shape, ValueKind::Intermediate, out_descs[i].type));
    }
    nodes_.push_back(std::move(n));
    return nodes_.back().outputs;
}

void Graph::output(int value, const std::string& name) {
    if (value < 0 || size_t(value) >= values_.size())
        throw Error("graph output '" + name + "': value does not exist");
    for (auto& [n, v] : outputs_)
        if (n == name) throw Error("duplicate graph output '" + name + "'");
    outputs_.push_back({name, value});
}

std::vector<int> Graph::producers() const {
    std::vector<int> producer(values_.size(), -1);
    for (size_t i = 0; i < nodes_.size(); ++i)
        for (int o : nodes_[i].outputs) producer[size_t(o)] = int(i);
    return producer;
}

std::vector<int> Graph::topo_order() const {
    // Kahn's algorithm, taking ready nodes in insertion order for a stable schedule.
    const std::vector<int> producer = producers();
    std::vector<int> missing;
    std::vector<std::vector<int>> consumers;
    dependencies(nodes_, producer, missing, consumers);
    std::vector<int> order, ready;
    for (size_t i = 0; i < nodes_.size(); ++i)
        if (!missing[i]) ready.push_back(int(i));
    while (!ready.empty()) {
        auto it = std::min_element(ready.begin(), ready.end());
        int n = *it;
        ready.erase(it);
        order.push_back(n);
        for (int c : consumers[size_t(n)])
            if (--missing[size_t(c)] == 0) ready.push_back(c);
    }
    if (order.size() != nodes_.size()) throw Error("graph has a cycle");
    return order;
}

std::vector<int> Graph::stepped_order(std::vector<int>* step, bool late) const {
    // Kahn's algorithm again, but a node that reads a value written in the
    // current step waits for the next one while any other ready node can go
    // now; lowest index first among those that can.
    const std::vector<int> producer = producers();
    std::vector<int> missing, step_of(nodes_.size(), -1);
    std::vector<std::vector<int>> consumers;
    dependencies(nodes_, producer, missing, consumers);
    std::vector<int> order, ready;
    for (size_t i = 0; i < nodes_.size(); ++i)
        if (!missing[i]) ready.push_back(int(i));
    int current = 0;
    auto free_now = [&](int n) {
        for (int in : nodes_[size_t(n)].inputs)
            if (int p = producer[size_t(in)]; p >= 0 && step_of[size_t(p)] == current) return false;
        return true;
    };
    while (!ready.empty()) {
        int pick = -1;
        for (int n : ready)
            if ((pick < 0 || n < pick) && free_now(n)) pick = n;
        if (pick < 0) {  // every ready node reads this step's outputs: a barrier
            ++current;
            pick = *std::min_element(ready.begin(), ready.end());
        }
        ready.erase(std::find(ready.begin(), ready.end(), pick));
        step_of[size_t(pick)] = current;
        order.push_back(pick);
        for (int c : consumers[size_t(pick)])
            if (--missing[size_t(c)] == 0) ready.push_back(c);
    }
    if (order.size() != nodes_.size()) throw Error("graph has a cycle");
    if (late)  // readers first: each node one step before its earliest reader, or in the last step
        for (auto it = order.rbegin(); it != order.rend(); ++it) {
            int s = current;
            for (int c : consumers[size_t(*it)]) s = std::min(s, step_of[size_t(c)] - 1);
            step_of[size_t(*it)] = s;
        }
    std::vector<int> rank(nodes_.size());
    for (size_t i = 0; i < order.size(); ++i) rank[size_t(order[i])] = int(i);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
        return step_of[size_t(a)] != step_of[size_t(b)] ? step_of[size_t(a)] < step_of[size_t(b)] : rank[size_t(a)] < rank[size_t(b)];
    });
    if (step) {
        step->clear();
        for (int n : order) step->push_back(step_of[size_t(n)]);
    }
    return order;
}

}  // namespace vtloc
