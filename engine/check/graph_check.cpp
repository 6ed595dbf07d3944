#include "engine/check/graph_check.h"

#include <chrono>
#include <cstdio>
#include <map>

#include "engine/check/fault_injection.h"
#include "engine/op.h"
#include "runtime/context.h"

namespace vtloc::check {

namespace {

thread_local std::map<std::string, std::function<void(HostTensor&)>> t_faults;

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

namespace testing {
void set_fault(const std::string& node, std::function<void(HostTensor&)> corrupt) {
    t_faults[node] = std::move(corrupt);
}
void clear_fault() { t_faults.clear(); }
void apply_fault(const std::string& name, HostTensor& t) {
    const auto f = t_faults.find(name);
    if (f != t_faults.end() && f->second) f->second(t);
}
}  // namespace testing

std::string dispatch_str(const std::string& shader, const std::vector<uint32_t>& spec, uint32_t texel_bindings,
                         const uint32_t groups[3]) {
    std::string s = shader + " spec=[";
    for (size_t i = 0; i < spec.size(); ++i) s += (i ? ", " : "") + std::to_string(spec[i]);
    s += "]";
    if (texel_bindings) {
        char hex[16];
        std::snprintf(hex, sizeof hex, "0x%x", texel_bindings);
        s += std::string(" texel=") + hex;
    }
    return s + " groups=" + std::to_string(groups[0]) + "x" + std::to_string(groups[1]) + "x" +
           std::to_string(groups[2]);
}

bool GraphCheck::ok() const {
    if (first_failure >= 0) return false;
    for (const OutputCheck& o : outputs)
        if (!o.cmp.ok) return false;
    return true;
}

GraphCheck check_graph(rt::Context& ctx, const Graph& g, const WeightStore& weights, const TensorMap& inputs,
                       Tolerance node_tol, Tolerance end_to_end_tol) {
    GpuExecutor exec(ctx, g, weights, false, /*keep_all=*/true);
    return check_graph(exec, g, weights, inputs, node_tol, end_to_end_tol);
}

GraphCheck check_graph(GpuExecutor& exec, const Graph& g, const WeightStore& weights, const TensorMap& inputs,
                       Tolerance node_tol, Tolerance end_to_end_tol) {
    GraphCheck r;
    auto t0 = std::chrono::steady_clock::now();
    TensorMap gpu_out = exec.run(inputs);
    r.gpu_ms = ms_since(t0);

    std::map<std::string, std::vector<std::string>> dispatches;
    for (const rt::Sequence::DispatchRecord& d : exec.sequence().dispatch_log())
        dispatches[d.node].push_back(dispatch_str(d.shader, d.spec, d.texel_bindings, d.groups));

    // What the GPU computed: every input and intermediate value.
    std::vector<HostTensor> gpu(g.values().size());
    std::vector<const HostTensor*> feed(g.values().size(), nullptr);
    for (size_t i = 0; i < g.values().size(); ++i) {
        const Value& v = g.values()[i];
        if (v.kind == ValueKind::Weight) feed[i] = &weights.get(v.name, v.shape);
        else if (v.kind == ValueKind::Input) feed[i] = &inputs.at(v.name);
        else feed[i] = &(gpu[i] = exec.value(int(i)));
    }
    for (const Node& n : g.nodes())
        if (!n.outputs.empty()) testing::apply_fault(n.name, gpu[size_t(n.outputs[0])]);

    // Each node's reference on the GPU's own inputs to it.
    t0 = std::chrono::steady_clock::now();
    for (int ni : g.topo_order()) {
        const Node& n = g.nodes()[size_t(ni)];
        NodeCheck c;
        c.node = n.name;
        c.op = n.op;
        c.dispatches = dispatches[n.name];
        std::vector<const HostTensor*> in;
        for (int id : n.inputs) {
            in.push_back(feed[size_t(id)]);
            c.input_shapes.push_back(g.value(id).shape);
        }
        std::vector<HostTensor> want;
        for (int id : n.outputs) {
            want.emplace_back(g.value(id).shape, g.value(id).type);
            c.output_shapes.push_back(g.value(id).shape);
        }
        std::vector<HostTensor*> out;
        for (HostTensor& t : want) out.push_back(&t);
        try {
            find_op(n.op).cpu(in, out, n.params);
        } catch (const std::exception& e) {
            c.error = e.what();
        }
        const uint32_t workspaces = find_op(n.op).workspace_outputs;
        if (c.error.empty())
            for (size_t k = 0; k < n.outputs.size(); ++k) {
                if ((workspaces >> k) & 1) continue;  // scratch: contents unspecified
                // Elements the op leaves unspecified take the reference's values, in a copy:
                // later nodes' references read what the GPU really wrote.
                HostTensor got = gpu[size_t(n.outputs[k])];
                if (const auto take = find_op(n.op).take_unspecified; take && k == 0) take(in, n.params, want[k], got);
                Comparison one = compare(got, want[k], node_tol);
                if (one.index) {
                    c.has_index = true;
                    c.indices_equal = c.indices_equal && one.ok;
                } else {
                    c.has_float = true;
                }
                if (!one.ok && n.outputs.size() > 1) one.detail = g.value(n.outputs[k]).name + " " + one.detail;
                merge(c.cmp, one);
            }
        if (!c.ok() && r.first_failure < 0) r.first_failure = int(r.nodes.size());
        r.nodes.push_back(std::move(c));
    }
    r.cpu_nodes_ms = ms_since(t0);

    // End to end: the graph's outputs against a CPU reference run of its own.
    t0 = std::chrono::steady_clock::now();
    TensorMap cpu_out = run_cpu(g, weights, inputs);
    r.cpu_full_ms = ms_since(t0);
    for (auto& [name, id] : g.outputs())
        r.outputs.push_back({name, compare(gpu_out.at(name), cpu_out.at(name), end_to_end_tol)});
    r.cpu_outputs = std::move(cpu_out);
    return r;
}

}  // namespace vtloc::check
