#include "bench/plan.h"

#include <algorithm>
#include <cstdio>
#include <map>

#include "bench/stages.h"
#include "engine/executor.h"

namespace vtloc::bench {

using nlohmann::json;

json plan_model(rt::Context& ctx, const WeightStore& weights, const ModelConfig& cfg, const HostTensor& image,
                const HostTensor& cloud) {
    const rt::DeviceInfo& d = ctx.info();
    VtlocRunner runner(weights, cfg, &ctx);
    VtlocRunner::Prepared p = runner.prepare_once(image, cloud, nullptr);
    GpuExecutor ex(ctx, p.graph, runner.weights());  // records; a plan-only context runs nothing
    std::map<std::string, std::string> op;
    for (const Node& n : p.graph.nodes()) op[n.name] = n.op;
    const uint64_t units = d.compute_units, target = rt::fill_workgroups(d);
    json nodes = json::array();
    std::map<std::string, std::vector<uint64_t>> by_stage;
    for (const rt::Sequence::DispatchRecord& r : ex.sequence().dispatch_log()) {
        const uint64_t wg = uint64_t(r.groups[0]) * r.groups[1] * r.groups[2];
        const std::string o = op.count(r.node) ? op.at(r.node) : "";
        const std::string st = stage_of(o, r.node);
        if (nodes.empty() || nodes.back()["name"] != r.node)
            nodes.push_back({{"name", r.node}, {"op", o}, {"stage", st}, {"workgroups", json::array()}, {"local", json::array()}});
        nodes.back()["workgroups"].push_back(wg);
        nodes.back()["local"].push_back(r.spec.empty() ? 1u : r.spec[0]);
        by_stage[st].push_back(wg);
    }
    json stages = json::object();
    for (auto& [st, v] : by_stage) {
        std::sort(v.begin(), v.end());
        const auto below = std::count_if(v.begin(), v.end(), [&](uint64_t w) { return w < std::max<uint64_t>(1, units); });
        stages[st] = {{"dispatches", v.size()}, {"fewest", v.front()}, {"median", v[v.size() / 2]}, {"most", v.back()},
                      {"below_compute_units", below}};
    }
    return {{"profile", d.name}, {"compute_units", units}, {"fill_target", target}, {"subgroup_size", d.subgroup_size},
            {"model", cfg.name}, {"dispatches", ex.sequence().dispatch_count()}, {"barriers", ex.sequence().barrier_count()},
            {"stages", stages}, {"nodes", nodes}};
}

void print_plan(const json& plan, FILE* f) {
    std::fprintf(f, "plan for %s (%llu compute units, subgroup %u; tile choices aim at %llu workgroups a dispatch)\n",
                 plan["profile"].get<std::string>().c_str(), (unsigned long long)plan["compute_units"].get<uint64_t>(),
                 plan["subgroup_size"].get<uint32_t>(), (unsigned long long)plan["fill_target"].get<uint64_t>());
    std::fprintf(f, "model %s: %llu dispatches, %llu barriers, recorded, not run\n\n", plan["model"].get<std::string>().c_str(),
                 (unsigned long long)plan["dispatches"].get<uint64_t>(), (unsigned long long)plan["barriers"].get<uint64_t>());
    std::fprintf(f, "%-12s %10s %8s %8s %8s %20s\n", "stage", "dispatches", "fewest", "median", "most", "below compute units");
    for (const auto& [st, s] : plan["stages"].items())
        std::fprintf(f, "%-12s %10llu %8llu %8llu %8llu %20llu\n", st.c_str(), (unsigned long long)s["dispatches"].get<uint64_t>(),
                     (unsigned long long)s["fewest"].get<uint64_t>(), (unsigned long long)s["median"].get<uint64_t>(),
                     (unsigned long long)s["most"].get<uint64_t>(), (unsigned long long)s["below_compute_units"].get<uint64_t>());
    std::fprintf(f, "\n%-40s %-14s %s\n", "node", "op", "workgroups (x local size) per dispatch");
    for (const json& n : plan["nodes"]) {
        std::string w;
        for (size_t i = 0; i < n["workgroups"].size(); ++i)
        {
            if (i) w += ' ';
            w += std::to_string(n["workgroups"][i].get<uint64_t>());
            w += 'x';
            w += std::to_string(n["local"][i].get<uint32_t>());
        }
        std::fprintf(f, "%-40s %-14s %s\n", n["name"].get<std::string>().c_str(), n["op"].get<std::string>().c_str(), w.c_str());
    }
}

}  // namespace vtloc::bench
