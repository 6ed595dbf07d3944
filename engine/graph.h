#pragma once
// A compute graph: values (inputs, weights, intermediates) and nodes (op +
// inputs + outputs + params). Output shapes are inferred when a node is added,
// so a bad shape is reported where the graph is built, naming the node.
#include <map>
#include <string>
#include <vector>

#include "engine/tensor.h"

namespace vtloc {

// Numeric op parameters (slope, activation code, axis ...).
class Params {
public:
    Params() = default;
    Params(std::initializer_list<std::pair<const std::string, double>> v) : values_(v) {}
    Params& set(const std::string& k, double v) { values_[k] = v; return *this; }
    double get(const std::string& k, double fallback) const {
        auto it = values_.find(k);
        return it == values_.end() ? fallback : it->second;
    }
    bool has(const std::string& k) const { return values_.count(k) != 0; }
    std::vector<std::string> keys() const {
        std::vector<std::string> k;
        for (const auto& [name, v] : values_) k.push_back(name);
        return k;
    }

private:
    std::map<std::string, double> values_;
};

enum class ValueKind { Input, Weight, Intermediate };

struct Value {
    std::string name;
    Shape shape;
    ValueKind kind = ValueKind::Intermediate;
    ElemType type = ElemType::F32;
};

struct Node {
    std::string op;
    std::string name;
    std::vector<int> inputs, outputs;
    Params params;
};

class Graph {
public:
    int input(const std::string& name, Shape shape, ElemType type = ElemType::F32);
    // A weight looked up by name (and checked for this shape) when the graph is run.
    // I32 weights (e.g. a surface's lookup grid) keep their integers bit for bit.
    int weight(const std::string& name, Shape shape, ElemType type = ElemType::F32);
    std::vector<int> add(const std::string& op, const std::vector<int>& inputs, Params params = {},
                         const std::string& name = {});
    int add1(const std::string& op, const std::vector<int>& inputs, Params params = {},
             const std::string& name = {}) {
        return add(op, inputs, std::move(params), name).at(0);
    }
    void output(int value, const std::string& name);

    const std::vector<Value>& values() const { return values_; }
    const Value& value(int id) const { return values_.at(size_t(id)); }
    const std::vector<Node>& nodes() const { return nodes_; }
    const std::vector<std::pair<std::string, int>>& outputs() const { return outputs_; }

    // Per value, the index of the node that writes it (-1: an input or weight).
    std::vector<int> producers() const;
    // Node indices such that every node comes after the producers of its inputs.
    std::vector<int> topo_order() const;
    // A topological order in steps: a step's nodes read nothing another node of
    // the same step writes, so a GPU may run them at once and one barrier
    // between steps orders them (independent branches, e.g. the tactile and
    // point encoders or a multi-scale layer's scales, share their barriers).
    // step[i] is the step of order[i], non-decreasing from 0. late: the same
    // number of steps, each node in the last step its readers allow (a side
    // branch then runs beside the main chain's later, longer nodes).
    std::vector<int> stepped_order(std::vector<int>* step, bool late = false) const;

private:
    int new_value(const std::string& name, Shape shape, ValueKind kind, ElemType type = ElemType::F32);
    std::vector<Value> values_;
    std::vector<Node> nodes_;
    std::vector<std::pair<std::string, int>> outputs_;
};

}  // namespace vtloc
