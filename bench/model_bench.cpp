#include "bench/model_bench.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <map>
#include <unistd.h>

#include "bench/clock.h"
#include "bench/flops.h"
#include "bench/stages.h"
#include "base/error.h"
#include "engine/io/object.h"

namespace vtloc::bench {

using nlohmann::json;

namespace {

using NodeRun = std::map<std::string, double>;  // label -> ms of one profiled run

struct Profile {
    std::vector<std::string> order;  // labels in schedule order
    std::vector<NodeRun> runs;
    std::map<std::string, std::string> op;  // label -> op
    std::map<std::string, double> flops;    // label -> FLOPs
    std::map<std::string, std::vector<uint64_t>> workgroups;  // label -> each dispatch's workgroups
};

// `reps` profiled runs of f after one to build the profiled recording.
template <class F>
Profile profile(VtlocRunner& r, int reps, F&& f, const std::map<std::string, HostTensor>& balls = {}) {
    Profile p;
    r.set_profiling(true);
    try {
        f();
        for (int i = 0; i < reps; ++i) {
            f();
            NodeRun run;
            for (auto& [label, ms] : r.last_node_times()) {
                if (!run.count(label) && p.runs.empty()) p.order.push_back(label);
                run[label] += ms;
            }
            p.runs.push_back(std::move(run));
            if (i == 0)
                for (const auto& [label, n] : r.last_dispatch_workgroups()) p.workgroups[label].push_back(n);
        }
    } catch (...) {
        r.set_profiling(false);
        throw;
    }
    r.set_profiling(false);
    if (const Graph* g = r.last_graph()) {
        for (const Node& n : g->nodes())
            if (!p.op.count(n.name)) p.op[n.name] = n.op;
        p.flops = node_flops(*g, balls);
    }
    return p;
}

// The balls of the point branch for `cloud` (node_flops: layers that skip ball padding).
std::map<std::string, HostTensor> balls_of(VtlocRunner& r, const HostTensor& image, const HostTensor& cloud) {
    VtlocRunner::Prepared p = r.prepare_once(image, cloud, nullptr);
    return ball_indices(p.graph, r.weights(), p.inputs);
}

double median_of(std::vector<double> v) { return v.empty() ? 0.0 : summarize(std::move(v)).median; }

// Per run, the sum of the nodes `pick` accepts.
template <class Pick>
std::vector<double> sums(const Profile& p, Pick&& pick) {
    std::vector<double> out;
    for (const NodeRun& run : p.runs) {
        double s = 0;
        for (auto& [label, ms] : run)
            if (pick(label)) s += ms;
        out.push_back(s);
    }
    return out;
}

std::string stage(const Profile& p, const std::string& label) {
    auto it = p.op.find(label);
    return stage_of(it == p.op.end() ? "" : it->second, label);
}

// GFLOP/s of the GEMM-like nodes of one stage, and the fraction of the probe.
json efficiency(const Profile& p, const std::string& st, double probe) {
    double flops = 0;
    for (auto& [label, f] : p.flops)
        if (stage(p, label) == st) flops += f;
    const double ms = median_of(sums(p, [&](const std::string& l) { return p.flops.count(l) && stage(p, l) == st; }));
    // Also each node's fastest run, summed: on a shared host busy phases only slow
    // nodes down, so this is the undisturbed estimate (bench/README.md).
    std::map<std::string, double> best;
    for (const NodeRun& run : p.runs)
        for (auto& [label, t] : run)
            if (p.flops.count(label) && stage(p, label) == st) best[label] = best.count(label) ? std::min(best[label], t) : t;
    double fastest = 0;
    for (auto& [label, t] : best) fastest += t;
    json j{{"gflop", flops * 1e-9}, {"ms", ms}, {"fastest_ms", fastest}};
    j["gflops"] = ms > 0 ? flops / (ms * 1e-3) * 1e-9 : 0.0;
    j["gflops_fastest"] = fastest > 0 ? flops / (fastest * 1e-3) * 1e-9 : 0.0;
    set_fractions_of_peak(j, probe);
    return j;
}

}  // namespace

void set_fractions_of_peak(json& e, double probe) {
    for (const char* k : {"", "_fastest"})
        e[std::string("fraction_of_peak") + k] =
            probe > 0 ? json(e[std::string("gflops") + k].get<double>() / probe) : json(nullptr);
}

namespace {

json nodes_json(const Profile& p) {
    json out = json::array();
    for (const std::string& label : p.order) {
        std::vector<double> ms;
        for (const NodeRun& run : p.runs) ms.push_back(run.count(label) ? run.at(label) : 0.0);
        const double med = median_of(ms);
        json n{{"name", label}, {"op", p.op.count(label) ? p.op.at(label) : ""}, {"stage", stage(p, label)}, {"ms", med}};
        if (p.flops.count(label) && med > 0) n["gflops"] = p.flops.at(label) / (med * 1e-3) * 1e-9;
        if (p.workgroups.count(label)) n["workgroups"] = p.workgroups.at(label);  // per dispatch, in order
        out.push_back(n);
    }
    return out;
}

bool has_ilu(const VtlocRunner& r) { return r.config().head == Head::Ilu; }

json ilu_sweep(VtlocRunner& r, const ModelBenchInputs& in, const ModelBenchOptions& opt) {
    json rows = json::array();
    std::vector<double> xs, e2e, head;
    double e2e0 = -1;
    for (int n : opt.iters) {
        TouchOptions o;
        o.iters = n;
        const std::vector<double> t = time_ms([&] { r.localize_once(in.image, in.cloud, nullptr, o); }, 1, opt.reps);
        Profile p = profile(r, opt.profile_reps, [&] { r.localize_once(in.image, in.cloud, nullptr, o); });
        const double ilu_ms = median_of(sums(p, [&](const std::string& l) { return stage(p, l) == "head"; }));
        const double med = median_of(t);
        if (n == 0) e2e0 = med;
        json row{{"n", n}, {"end_to_end_ms", stats_json(t)}, {"ilu_gpu_ms", ilu_ms}};
        row["ms_per_iter"] = (n > 0 && e2e0 >= 0) ? json((med - e2e0) / n) : json(nullptr);
        rows.push_back(row);
        xs.push_back(n), e2e.push_back(med), head.push_back(ilu_ms);
    }
    json out{{"table", rows}};
    if (xs.size() >= 2)
        out["slope_ms_per_iter"] = {{"end_to_end", slope(xs, e2e)}, {"ilu_node", slope(xs, head)}};
    return out;
}

// The head recorded one dispatch per iteration: the time of each iteration
// from the timestamps between them.
json ilu_stepped(VtlocRunner& r, const EncodedObject& obj, const ModelBenchInputs& in, const ModelBenchOptions& opt) {
    const int n = opt.stepped_iters;
    TouchOptions o;
    o.iters = n;
    r.set_ilu_stepped(true);
    Profile p;
    try {
        p = profile(r, opt.profile_reps, [&] { r.localize(obj, {in.image}, o); });
    } catch (...) {
        r.set_ilu_stepped(false);
        throw;
    }
    r.set_ilu_stepped(false);
    std::vector<double> first, iter, pass;
    for (const NodeRun& run : p.runs)
        for (auto& [label, ms] : run) {
            if (label.rfind("ilu.step", 0) != 0) continue;
            const int k = std::stoi(label.substr(8));
            (k == 0 ? first : k < n ? iter : pass).push_back(ms);
        }
    json out{{"n", n}, {"first_step_ms", stats_json(first)}, {"per_iteration_ms", stats_json(iter)},
             {"pass_through_step_ms", stats_json(pass)}};
    // Per step, the median over runs: the iteration-by-iteration timeline.
    json steps = json::array();
    for (int k = 0; k < n; ++k) {
        std::vector<double> v;
        for (const NodeRun& run : p.runs)
            if (run.count("ilu.step" + std::to_string(k))) v.push_back(run.at("ilu.step" + std::to_string(k)));
        steps.push_back(median_of(v));
    }
    out["step_ms"] = steps;
    return out;
}

// Where the ILU and retrieval are one node (engine/ops/ilu_retrieve.cpp: one
// dispatch where the device allows), the retrieval's cost is what it adds to
// the head node: the head as built, then with retrieval in a node of its own,
// profiled in turns so that drift on a shared machine falls on both. On the CPU
// reference the same split times the reference retrieval alone.
json retrieval_split(VtlocRunner& r, const EncodedObject& obj, const ModelBenchInputs& in, const ModelBenchOptions& opt) {
    auto run = [&] { r.localize(obj, {in.image}, TouchOptions{}); };
    auto of = [](const Profile& p, const char* st) {
        return median_of(sums(p, [&](const std::string& l) { return stage(p, l) == st; }));
    };
    std::vector<double> fused, head, node;
    bool one_dispatch = false;
    for (int round = 0, rounds = r.on_gpu() ? 3 : 1; round < rounds; ++round) {  // the reference is slow and steady
        Profile f = profile(r, opt.profile_reps, run);
        for (const std::string& s : r.last_dispatch_shaders()) one_dispatch = one_dispatch || s == "ilu_retrieve";
        r.set_retrieval_apart(true);
        Profile a;
        try {
            a = profile(r, opt.profile_reps, run);
        } catch (...) {
            r.set_retrieval_apart(false);
            throw;
        }
        r.set_retrieval_apart(false);
        if (of(f, "retrieval") > 0) return nullptr;  // not fused in this graph: the stage table has it
        fused.push_back(of(f, "head"));
        head.push_back(of(a, "head"));
        node.push_back(of(a, "retrieval"));
    }
    const double fm = median_of(fused), hm = median_of(head);
    json out{{"fused_head_ms", fm}, {"head_alone_ms", hm}, {"epilogue_ms", fm - hm}, {"node_ms", median_of(node)}};
    if (r.on_gpu()) out["one_dispatch"] = one_dispatch;  // false: the two ops' dispatches inside the node
    return out;
}

json point_sweep(VtlocRunner& r, const ModelBenchInputs& in, const ModelBenchOptions& opt) {
    json rows = json::array();
    for (int64_t n : opt.points) {
        HostTensor cloud = io::load_object(in.object, n);
        const std::vector<double> t = time_ms([&] { r.encode_object(cloud); }, 1, opt.reps);
        Profile p = profile(r, opt.profile_reps, [&] { r.encode_object(cloud); }, balls_of(r, in.image, cloud));
        auto of_op = [&](const char* op) {
            return median_of(sums(p, [&](const std::string& l) { return p.op.count(l) && p.op.at(l) == op; }));
        };
        const double total = median_of(sums(p, [](const std::string&) { return true; }));
        json row{{"points", n}, {"encode_ms", stats_json(t)}, {"node_sum_ms", total},
                 {"fps_ms", of_op("fps")}, {"ball_query_ms", of_op("ball_query")},
                 {"mlp", efficiency(p, "point", in.probe_gflops)}};
        rows.push_back(row);
    }
    return rows;
}

// End to end under each of the executor's node orders (engine/executor.h
// Schedule), in turns so that drift on a shared machine falls on all of them;
// with the barriers each recording has. The runner is left on the default.
json schedules(VtlocRunner& r, const std::function<void()>& once, const ModelBenchOptions& opt) {
    const Schedule all[] = {Schedule::Serial, Schedule::Steps, Schedule::Late};
    std::map<std::string, std::vector<double>> t;
    std::map<std::string, uint32_t> barriers;
    try {
        for (int round = 0; round < 3; ++round)
            for (Schedule s : all) {
                r.set_schedule(s);
                std::vector<double> v = time_ms(once, round == 0 ? 2 : 1, std::max(1, opt.reps / 2));
                t[schedule_name(s)].insert(t[schedule_name(s)].end(), v.begin(), v.end());
                barriers[schedule_name(s)] = r.last_barriers();
            }
    } catch (...) {
        r.set_schedule(Schedule::Steps);
        throw;
    }
    r.set_schedule(Schedule::Steps);
    json out = json::object();
    for (Schedule s : all)
        out[schedule_name(s)] = {{"end_to_end_ms", stats_json(t[schedule_name(s)])}, {"barriers", barriers[schedule_name(s)]}};
    return out;
}

// Progress on stderr for people watching a long run; silent when stderr is
// not a terminal (scripts and the smoke test see no stray lines).
void progress(const std::string& what) {
    if (isatty(2)) std::fprintf(stderr, "vtloc-bench: %s...\n", what.c_str());
}

}  // namespace

json stats_json(const std::vector<double>& samples) {
    if (samples.empty()) return nullptr;
    Stats s = summarize(samples);
    return {{"median", s.median}, {"p10", s.p10}, {"p90", s.p90}, {"min", s.min}, {"n", samples.size()}};
}

void time_node(GpuExecutor& exec, const TensorMap& in, const std::string& label, int reps, json& row) {
    exec.run(in);
    std::vector<double> ms;
    for (int r = 0; r < reps; ++r) {
        exec.run(in);
        for (const auto& t : exec.node_times())
            if (t.label == label) ms.push_back(t.ms);
    }
    const auto& log = exec.sequence().dispatch_log();
    if (!log.empty()) {
        row["shader"] = log.back().shader;
        row["workgroup"] = log.back().spec.empty() ? 0u : log.back().spec.at(0);
    }
    row["ms"] = stats_json(ms);
}

json measure_model(VtlocRunner& r, const ModelBenchInputs& in, const ModelBenchOptions& opt) {
    json out;
    const TouchOptions defaults;
    auto once = [&] { r.localize_once(in.image, in.cloud, nullptr, defaults); };

    progress(std::string(r.on_gpu() ? "GPU" : "CPU reference") + ": first run and end to end");
    auto t0 = std::chrono::steady_clock::now();
    once();  // builds and records the graph; lavapipe also compiles shaders here
    out["first_run_ms"] = ms_since(t0);
    out["end_to_end_ms"] = stats_json(time_ms(once, opt.warmup, opt.reps));
    const VtlocRunner::MemoryUse mem = r.last_memory();
    out["memory"] = {{"weights_bytes", mem.weight_bytes}, {"activations_peak_bytes", mem.arena_bytes},
                     {"activations_unplanned_bytes", mem.unplanned_bytes},
                     {"total_bytes", mem.weight_bytes + mem.arena_bytes}};

    progress("per stage and per node");
    Profile p = profile(r, opt.profile_reps, once, balls_of(r, in.image, in.cloud));
    json stages = json::object();
    for (const std::string& st : stage_names()) {
        std::vector<double> v = sums(p, [&](const std::string& l) { return stage(p, l) == st; });
        if (std::any_of(v.begin(), v.end(), [](double x) { return x > 0; })) stages[st] = stats_json(v);
    }
    std::vector<double> other = sums(p, [&](const std::string& l) { return stage(p, l) == "other"; });
    if (std::any_of(other.begin(), other.end(), [](double x) { return x > 0; })) stages["other"] = stats_json(other);
    stages["total"] = stats_json(sums(p, [](const std::string&) { return true; }));
    out["stages_ms"] = stages;
    out["nodes"] = nodes_json(p);
    out["efficiency"] = {{"conv", efficiency(p, "tactile", in.probe_gflops)},
                         {"mlp", efficiency(p, "point", in.probe_gflops)}};

    progress("cached object and batches");
    EncodedObject obj = r.encode_object(in.cloud);
    out["cached_touch_ms"] = stats_json(time_ms([&] { r.localize(obj, {in.image}, defaults); }, opt.warmup, opt.reps));
    json batches = json::array();
    for (int b : opt.batches) {
        if (b < 1) throw Error("batch sizes must be >= 1, got " + std::to_string(b));
        std::vector<HostTensor> images(size_t(b), in.image);
        std::vector<double> t = time_ms([&] { r.localize(obj, images, defaults); }, 1, opt.reps);
        const double med = median_of(t);
        batches.push_back({{"batch", b}, {"ms", stats_json(t)}, {"touches_per_s", med > 0 ? 1e3 * b / med : 0.0}});
    }
    out["batch"] = batches;

    if (has_ilu(r)) {
        progress("ILU sweep over N");
        out["ilu"] = ilu_sweep(r, in, opt);
        if (opt.stepped_iters > 0) out["ilu"]["stepped"] = ilu_stepped(r, obj, in, opt);
        progress("retrieval in the ILU's dispatch and apart");
        json split = retrieval_split(r, obj, in, opt);
        if (!split.is_null()) out["retrieval_split"] = split;
    }
    if (!opt.points.empty()) progress("point sweep");
    if (!opt.points.empty()) out["points"] = point_sweep(r, in, opt);
    // End to end again, after everything above: on a fresh NVIDIA machine the runs just
    // after the first one were 4x slower in some processes (docs/performance.md, "Real GPU").
    if (r.on_gpu()) {
        out["end_to_end_late_ms"] = stats_json(time_ms(once, 1, opt.reps));
        // After every shape above: the weights are held once, whatever the shape count.
        const VtlocRunner::AllMemory all = r.all_memory();
        out["memory_all_shapes"] = {{"graphs", all.graphs}, {"weights_resident_bytes", all.resident_weight_bytes},
                                    {"weights_if_per_graph_bytes", all.weight_bytes_by_graph},
                                    {"activations_bytes", all.arena_bytes}};
        // Last: its two other orders are graphs of their own, which the count above leaves out.
        progress("end to end by schedule");
        out["schedules"] = schedules(r, once, opt);
    }
    return out;
}

}  // namespace vtloc::bench
