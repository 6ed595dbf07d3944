#include "engine/executor.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstring>
#include <set>

#include "base/error.h"
#include "engine/op.h"
#include "runtime/context.h"

namespace vtloc {

namespace {

void check_input(const Value& v, const HostTensor& t) {
    if (t.shape != v.shape)
        throw Error("graph input '" + v.name + "' has shape " + shape_str(t.shape) + ", expected " + shape_str(v.shape));
    if (t.type != v.type)
        throw Error("graph input '" + v.name + "' has element type " + elem_type_name(t.type) + ", expected " +
                    elem_type_name(v.type));
    if (int64_t(t.data.size()) != numel(v.shape))
        throw Error("graph input '" + v.name + "': data size does not match its shape");
}

}  // namespace

void check_inputs(const Graph& g, const TensorMap& inputs) {
    size_t n = 0;
    for (const Value& v : g.values()) {
        if (v.kind != ValueKind::Input) continue;
        ++n;
        auto it = inputs.find(v.name);
        if (it == inputs.end()) throw Error("graph input '" + v.name + "' was not given");
        check_input(v, it->second);
    }
    if (inputs.size() != n)
        for (auto& [name, t] : inputs) {
            bool known = false;
            for (const Value& v : g.values()) known |= v.kind == ValueKind::Input && v.name == name;
            if (!known) throw Error("'" + name + "' is not an input of this graph");
        }
}

namespace {

// Runs the CPU reference of the nodes marked in `run`, in schedule order, into
// vals; an input or weight is looked up when a node first reads it (the caller has
// checked the inputs those nodes read).
std::vector<HostTensor> run_nodes(const Graph& g, const WeightStore& weights, const TensorMap& inputs,
                                  const std::vector<char>& run, std::vector<NodeMs>* node_ms) {
    std::vector<HostTensor> vals(g.values().size());
    std::vector<const HostTensor*> ptr(g.values().size(), nullptr);
    for (int ni : g.topo_order()) {
        if (!run[size_t(ni)]) continue;
        const Node& n = g.nodes()[size_t(ni)];
        std::vector<const HostTensor*> in;
        std::vector<HostTensor*> out;
        for (int id : n.inputs) {
            const Value& v = g.value(id);
            if (!ptr[size_t(id)] && v.kind == ValueKind::Weight) ptr[size_t(id)] = &weights.get(v.name, v.shape);
            if (!ptr[size_t(id)] && v.kind == ValueKind::Input) ptr[size_t(id)] = &inputs.at(v.name);  // checked by the caller
            in.push_back(ptr[size_t(id)]);
        }
        for (int id : n.outputs) {
            vals[size_t(id)] = HostTensor(g.value(id).shape, g.value(id).type);
            ptr[size_t(id)] = &vals[size_t(id)];
            out.push_back(&vals[size_t(id)]);
        }
        const auto t0 = std::chrono::steady_clock::now();
        find_op(n.op).cpu(in, out, n.params);
        if (node_ms)
            node_ms->push_back({n.name, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count()});
    }
    return vals;  // inputs and weights stay where they are: callers look them up
}

// Value `id` after run_nodes: a node's output, or an input or weight itself.
const HostTensor& value_of(const Graph& g, const WeightStore& weights, const TensorMap& inputs,
                           const std::vector<HostTensor>& vals, int id) {
    const Value& v = g.value(id);
    if (v.kind == ValueKind::Weight) return weights.get(v.name, v.shape);
    if (v.kind == ValueKind::Input) return inputs.at(v.name);  // checked by the caller
    return vals[size_t(id)];
}

}  // namespace

TensorMap run_cpu(const Graph& g, const WeightStore& weights, const TensorMap& inputs, std::vector<NodeMs>* node_ms) {
    if (node_ms) node_ms->clear();
    check_inputs(g, inputs);
    const std::vector<HostTensor> vals = run_nodes(g, weights, inputs, std::vector<char>(g.nodes().size(), 1), node_ms);
    TensorMap result;
    for (auto& [name, id] : g.outputs()) result[name] = value_of(g, weights, inputs, vals, id);
    return result;
}

std::map<int, HostTensor> run_cpu_values(const Graph& g, const WeightStore& weights, const TensorMap& inputs,
                                         const std::vector<int>& wanted) {
    const std::vector<int> producer = g.producers();
    std::vector<char> run(g.nodes().size(), 0);
    std::vector<int> todo;
    for (int id : wanted) {
        if (id < 0 || size_t(id) >= g.values().size())
            throw Error("run_cpu_values: value id " + std::to_string(id) + " is not in this graph (" +
                        std::to_string(g.values().size()) + " values)");
        if (producer[size_t(id)] >= 0) todo.push_back(producer[size_t(id)]);
    }
    while (!todo.empty()) {
        const int n = todo.back();
        todo.pop_back();
        if (run[size_t(n)]) continue;
        run[size_t(n)] = 1;
        for (int id : g.nodes()[size_t(n)].inputs)
            if (producer[size_t(id)] >= 0) todo.push_back(producer[size_t(id)]);
    }
    // Only the inputs read (by a node that runs, or wanted as they are) must be given.
    auto check = [&](int id, const Node* reader) {
        const Value& v = g.value(id);
        if (v.kind != ValueKind::Input) return;
        auto it = inputs.find(v.name);
        if (it == inputs.end())
            throw Error(reader ? "node '" + reader->name + "' needs input '" + v.name + "', not given"
                               : "input '" + v.name + "' is not given");
        check_input(v, it->second);
    };
    for (size_t n = 0; n < run.size(); ++n)
        if (run[n])
            for (int id : g.nodes()[n].inputs) check(id, &g.nodes()[n]);
    for (int id : wanted) check(id, nullptr);
    const std::vector<HostTensor> vals = run_nodes(g, weights, inputs, run, nullptr);
    std::map<int, HostTensor> out;
    for (int id : wanted) out[id] = value_of(g, weights, inputs, vals, id);
    return out;
}

MemoryPlan plan_memory(const Graph& g, const std::vector<int>& order, uint64_t alignment, bool share,
                       const std::vector<int>& step) {
    if (!step.empty() && step.size() != order.size())
        throw Error("plan_memory: " + std::to_string(step.size()) + " steps for " + std::to_string(order.size()) +
                    " nodes");
    const size_t nv = g.values().size();
    std::vector<int> first(nv, INT_MAX), last(nv, -2);
    for (size_t i = 0; i < nv; ++i)
        if (g.values()[i].kind == ValueKind::Input) first[i] = last[i] = -1;
    for (size_t pos = 0; pos < order.size(); ++pos) {
        const Node& n = g.nodes()[size_t(order[pos])];
        const int t = step.empty() ? int(pos) : step[pos];
        for (int id : n.outputs) first[size_t(id)] = last[size_t(id)] = t;
        for (int id : n.inputs) last[size_t(id)] = std::max(last[size_t(id)], t);
    }
    for (auto& [name, id] : g.outputs()) last[size_t(id)] = INT_MAX;

    MemoryPlan plan;
    plan.offset.assign(nv, -1);
    std::vector<uint64_t> bytes(nv, 0);
    std::vector<size_t> todo;
    for (size_t i = 0; i < nv; ++i) {
        if (g.values()[i].kind == ValueKind::Weight) continue;
        bytes[i] = (std::max<uint64_t>(4, uint64_t(numel(g.values()[i].shape)) * 4) + alignment - 1) /
                   alignment * alignment;
        plan.total_bytes += bytes[i];
        todo.push_back(i);
    }
    // Largest first, each at the lowest offset free of every placed value whose
    // lifetime overlaps its own.
    std::stable_sort(todo.begin(), todo.end(), [&](size_t a, size_t b) { return bytes[a] > bytes[b]; });
    std::vector<size_t> placed;
    for (size_t v : todo) {
        std::vector<std::pair<uint64_t, uint64_t>> busy;
        for (size_t u : placed)
            if (!share || (first[u] <= last[v] && first[v] <= last[u]))
                busy.push_back({uint64_t(plan.offset[u]), uint64_t(plan.offset[u]) + bytes[u]});
        std::sort(busy.begin(), busy.end());
        uint64_t at = 0;
        for (auto& [b, e] : busy) {
            if (at + bytes[v] <= b) break;
            at = std::max(at, e);
        }
        plan.offset[v] = int64_t(at);
        plan.arena_bytes = std::max(plan.arena_bytes, at + bytes[v]);
        placed.push_back(v);
    }
    return plan;
}

const char* schedule_name(Schedule s) {
    return s == Schedule::Steps ? "steps" : s == Schedule::Late ? "late" : "serial";
}

GpuExecutor::GpuExecutor(rt::Context& ctx, const Graph& g, const WeightStore& weights, bool profile,
                         bool keep_all)
    : GpuExecutor(ctx, g, weights, std::make_shared<ResidentWeights>(ctx), profile, keep_all) {}

GpuExecutor::GpuExecutor(rt::Context& ctx, const Graph& g, const WeightStore& weights,
                         std::shared_ptr<ResidentWeights> resident, bool profile, bool keep_all, Schedule schedule)
    : ctx_(ctx), graph_(g), resident_(std::move(resident)) {
    const uint64_t align = ctx_.info().tensor_alignment();
    seq_ = std::make_unique<rt::Sequence>(ctx_, profile);

    try {
        build(weights, align, keep_all, profile ? Schedule::Serial : schedule);
    } catch (...) {
        // What this build made is freed by the members' own destructors; the
        // weights it alone uploaded go back too.
        seq_.reset();
        if (uploaded_ != ResidentWeights::kNone) resident_->forget(uploaded_);
        throw;
    }
}

void GpuExecutor::build(const WeightStore& weights, uint64_t align, bool keep_all, Schedule schedule) {
    uploaded_ = resident_->ensure(graph_, weights);
    std::set<std::string> read;
    for (const Value& v : graph_.values())
        if (v.kind == ValueKind::Weight && read.insert(v.name).second) weight_bytes_ += resident_->view(v.name).size;

    std::vector<uint64_t> scratch(graph_.nodes().size(), 0), scratch_at(graph_.nodes().size(), 0);
    for (size_t ni = 0; ni < graph_.nodes().size(); ++ni) {
        const Node& n = graph_.nodes()[ni];
        const OpDef& op = find_op(n.op);
        if (!op.scratch_bytes) continue;
        std::vector<Shape> shapes;
        for (int id : n.inputs) shapes.push_back(graph_.value(id).shape);
        try {
            scratch[ni] = op.scratch_bytes(ctx_.info(), shapes, n.params);
        } catch (const Error& e) {
            throw Error("node '" + n.name + "' (" + n.op + "): " + e.what());
        }
    }
    if (schedule == Schedule::Serial) {
        order_ = graph_.topo_order();
        for (size_t i = 0; i < order_.size(); ++i) step_.push_back(int(i));
    } else {
        order_ = graph_.stepped_order(&step_, schedule == Schedule::Late);
        for (size_t b = 0, e = 0; b < order_.size(); b = e) {  // a step's scratch users first
            while (e < order_.size() && step_[e] == step_[b]) ++e;
            std::stable_partition(order_.begin() + long(b), order_.begin() + long(e),
                                  [&](int n) { return scratch[size_t(n)] > 0; });
        }
    }

    // Activations: one arena, reused across values with disjoint lifetimes.
    plan_ = plan_memory(graph_, order_, align, !keep_all, step_);
    arena_ = rt::Buffer(ctx_, plan_.arena_bytes, rt::MemoryKind::Device);
    // Scratch: a step's nodes side by side (they may run at once), steps
    // reusing the same bytes (a barrier lies between them).
    uint64_t step_bytes = 0;
    for (size_t pos = 0; pos < order_.size(); ++pos) {
        if (pos > 0 && step_[pos] != step_[pos - 1]) step_bytes = 0;
        const size_t ni = size_t(order_[pos]);
        if (!scratch[ni]) continue;
        scratch_at[ni] = step_bytes;
        step_bytes += (scratch[ni] + align - 1) / align * align;
        plan_.scratch_bytes = std::max(plan_.scratch_bytes, step_bytes);
    }
    if (plan_.scratch_bytes) scratch_ = rt::Buffer(ctx_, plan_.scratch_bytes, rt::MemoryKind::Device);

    uint64_t in_bytes = 0, out_bytes = 0;
    for (const Value& v : graph_.values())
        if (v.kind == ValueKind::Input) {
            in_offsets_[v.name] = in_bytes;
            in_bytes += uint64_t(numel(v.shape)) * 4;
        }
    for (auto& [name, id] : graph_.outputs()) {
        out_offsets_[name] = out_bytes;
        out_bytes += uint64_t(numel(graph_.value(id).shape)) * 4;
    }
    staging_in_ = rt::Buffer(ctx_, in_bytes, rt::MemoryKind::Staging);
    staging_out_ = rt::Buffer(ctx_, out_bytes, rt::MemoryKind::Staging);
    if (keep_all) staging_all_ = rt::Buffer(ctx_, plan_.arena_bytes, rt::MemoryKind::Staging);

    // The whole graph: one command buffer, recorded once.
    seq_->begin();
    for (size_t i = 0; i < graph_.values().size(); ++i) {
        const Value& v = graph_.values()[i];
        if (v.kind != ValueKind::Input) continue;
        uint64_t n = uint64_t(numel(v.shape)) * 4;
        seq_->copy({staging_in_.handle(), in_offsets_[v.name], n}, {arena_.handle(), uint64_t(plan_.offset[i]), n});
    }
    for (int ni : order_) {
        const Node& n = graph_.nodes()[size_t(ni)];
        std::vector<GpuTensor> in, out;
        for (int id : n.inputs) in.push_back({view_of(id), graph_.value(id).shape});
        for (int id : n.outputs) out.push_back({view_of(id), graph_.value(id).shape});
        seq_->begin_node(n.name);
        try {
            const rt::BufferView sv = scratch[size_t(ni)]
                                          ? rt::BufferView{scratch_.handle(), scratch_at[size_t(ni)], scratch[size_t(ni)]}
                                          : rt::BufferView{};
            find_op(n.op).gpu(GpuOpArgs{ctx_, *seq_, in, out, n.params, sv});
        } catch (const Error& e) {
            throw Error("node '" + n.name + "' (" + n.op + "): " + e.what());
        }
        seq_->end_node();
    }
    for (auto& [name, id] : graph_.outputs()) {
        rt::BufferView src = view_of(id);
        uint64_t n = uint64_t(numel(graph_.value(id).shape)) * 4;
        seq_->copy({src.buffer, src.offset, n}, {staging_out_.handle(), out_offsets_[name], n});
    }
    if (keep_all) seq_->copy({arena_.handle(), 0, plan_.arena_bytes}, {staging_all_.handle(), 0, plan_.arena_bytes});
    seq_->end();
}

GpuExecutor::~GpuExecutor() = default;

rt::BufferView GpuExecutor::view_of(int value) const {
    const Value& v = graph_.value(value);
    if (v.kind == ValueKind::Weight) return resident_->view(v.name);
    return {arena_.handle(), uint64_t(plan_.offset[size_t(value)]),
            std::max<uint64_t>(4, uint64_t(numel(v.shape)) * 4)};
}

HostTensor GpuExecutor::value(int id) const {
    const Value& v = graph_.value(id);
    if (!staging_all_.mapped()) throw Error("GpuExecutor::value needs an executor made with keep_all");
    if (v.kind == ValueKind::Weight) throw Error("GpuExecutor::value: '" + v.name + "' is a weight");
    HostTensor t(v.shape, v.type);
    if (!t.data.empty())
        std::memcpy(t.data.data(), static_cast<const char*>(staging_all_.mapped()) + plan_.offset[size_t(id)],
                    t.data.size() * 4);
    return t;
}

TensorMap GpuExecutor::run(const TensorMap& inputs) {
    check_inputs(graph_, inputs);
    for (auto& [name, t] : inputs)
        if (!t.data.empty())  // an empty vector's data() may be null: not for memcpy
            std::memcpy(static_cast<char*>(staging_in_.mapped()) + in_offsets_.at(name), t.data.data(),
                        t.data.size() * 4);
    seq_->submit_and_wait();
    TensorMap out;
    for (auto& [name, id] : graph_.outputs()) {
        HostTensor t(graph_.value(id).shape, graph_.value(id).type);
        if (!t.data.empty())
            std::memcpy(t.data.data(), static_cast<const char*>(staging_out_.mapped()) + out_offsets_.at(name),
                        t.data.size() * 4);
        out[name] = std::move(t);
    }
    return out;
}

}  // namespace vtloc
