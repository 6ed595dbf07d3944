#include "bench/report.h"

#include <algorithm>
#include <map>

#include "bench/stages.h"

namespace vtloc::bench {

using nlohmann::json;

namespace {

double med(const json& stats) { return stats.is_object() ? stats.at("median").get<double>() : 0.0; }

void stats_line(std::FILE* f, const char* what, const json& s) {
    if (!s.is_object()) return;
    std::fprintf(f, "  %-34s %9.2f ms  (p10 %.2f, p90 %.2f, n %d)\n", what, s["median"].get<double>(),
                 s["p10"].get<double>(), s["p90"].get<double>(), s["n"].get<int>());
}

double mib(const json& bytes) { return bytes.get<double>() / (1024.0 * 1024.0); }

void backend(std::FILE* f, const std::string& name, const json& b) {
    std::fprintf(f, "\n== %s ==\n", name.c_str());
    std::fprintf(f, "  first run (graph build, upload%s): %.0f ms\n", name == "gpu" ? ", shader compile" : "",
                 b["first_run_ms"].get<double>());
    stats_line(f, "end to end (wall, one touch)", b["end_to_end_ms"]);
    if (b.contains("schedules"))
        for (const auto& [name, sc] : b["schedules"].items())
            stats_line(f, ("end to end, " + name + " (" + std::to_string(sc["barriers"].get<uint32_t>()) + " barriers)").c_str(),
                       sc["end_to_end_ms"]);
    if (b.contains("end_to_end_late_ms")) stats_line(f, "end to end again, after the rest", b["end_to_end_late_ms"]);
    stats_line(f, "touch on a cached object (wall)", b["cached_touch_ms"]);
    if (name == "gpu") {
        const json& m = b["memory"];
        std::fprintf(f, "  device memory: weights %.2f MiB + activations peak %.2f MiB = %.2f MiB"
                        " (one buffer per activation would take %.2f MiB)\n",
                     mib(m["weights_bytes"]), mib(m["activations_peak_bytes"]), mib(m["total_bytes"]),
                     mib(m["activations_unplanned_bytes"]));
        if (b.contains("memory_all_shapes")) {
            const json& a = b["memory_all_shapes"];
            std::fprintf(f, "  after all %d graph shapes: weights %.2f MiB, resident once (one copy per graph would be"
                            " %.2f MiB) + activations %.2f MiB\n",
                         a["graphs"].get<int>(), mib(a["weights_resident_bytes"]), mib(a["weights_if_per_graph_bytes"]),
                         mib(a["activations_bytes"]));
        }
    }
    std::fprintf(f, "\n  per stage (%s, median of profiled runs)\n", name == "gpu" ? "GPU timestamps" : "CPU wall per node");
    const json& st = b["stages_ms"];
    const double total = med(st["total"]);
    std::vector<std::string> names = stage_names();
    names.push_back("other");
    names.push_back("total");
    for (const std::string& s : names)
        if (st.contains(s))
            std::fprintf(f, "    %-12s %9.2f ms  %5.1f%%   (p10 %.2f, p90 %.2f)\n", s.c_str(), med(st[s]),
                         total > 0 ? 100 * med(st[s]) / total : 0.0, st[s]["p10"].get<double>(), st[s]["p90"].get<double>());
    for (const char* k : {"conv", "mlp"}) {
        const json& e = b["efficiency"][k];
        if (e["gflop"].get<double>() <= 0) continue;
        std::fprintf(f, "  %-4s %.2f GFLOP in %.2f ms = %.1f GFLOP/s", k, e["gflop"].get<double>(), e["ms"].get<double>(),
                     e["gflops"].get<double>());
        if (!e["fraction_of_peak"].is_null()) std::fprintf(f, " = %.0f%% of the probe", 100 * e["fraction_of_peak"].get<double>());
        std::fprintf(f, "; fastest nodes %.2f ms = %.1f GFLOP/s", e["fastest_ms"].get<double>(), e["gflops_fastest"].get<double>());
        if (!e["fraction_of_peak_fastest"].is_null()) std::fprintf(f, " = %.0f%%", 100 * e["fraction_of_peak_fastest"].get<double>());
        std::fprintf(f, "\n");
    }
    // How many workgroups each stage's dispatches offer (a GPU needs several per compute unit).
    std::map<std::string, std::vector<uint64_t>> wg;
    if (b.contains("nodes"))
        for (const json& n : b["nodes"])
            if (n.contains("workgroups"))
                for (const json& w : n["workgroups"]) wg[n["stage"].get<std::string>()].push_back(w.get<uint64_t>());
    if (!wg.empty()) std::fprintf(f, "  workgroups per dispatch (fewest / median / most)\n");
    for (auto& [s, v] : wg) {
        std::sort(v.begin(), v.end());
        std::fprintf(f, "    %-12s %4zu dispatches  %llu / %llu / %llu\n", s.c_str(), v.size(), (unsigned long long)v.front(),
                     (unsigned long long)v[v.size() / 2], (unsigned long long)v.back());
    }

    std::fprintf(f, "\n  batch    median ms   touches/s\n");
    for (const json& r : b["batch"])
        std::fprintf(f, "  %5d %12.2f %11.1f\n", r["batch"].get<int>(), med(r["ms"]), r["touches_per_s"].get<double>());

    if (b.contains("ilu")) {
        const json& ilu = b["ilu"];
        std::fprintf(f, "\n  ILU sweep (paper style)\n      N   end-to-end ms   ms/iter vs N=0   ILU node ms\n");
        for (const json& r : ilu["table"]) {
            std::fprintf(f, "  %5d %15.2f", r["n"].get<int>(), med(r["end_to_end_ms"]));
            if (r["ms_per_iter"].is_null()) std::fprintf(f, " %16s", "-");
            else std::fprintf(f, " %16.3f", r["ms_per_iter"].get<double>());
            std::fprintf(f, " %13.3f\n", r["ilu_gpu_ms"].get<double>());
        }
        if (ilu.contains("slope_ms_per_iter"))
            std::fprintf(f, "  slope over N: %.4f ms/iter end to end, %.4f ms/iter in the ILU node\n",
                         ilu["slope_ms_per_iter"]["end_to_end"].get<double>(),
                         ilu["slope_ms_per_iter"]["ilu_node"].get<double>());
        if (ilu.contains("stepped") && ilu["stepped"]["per_iteration_ms"].is_object()) {
            const json& s = ilu["stepped"];
            std::fprintf(f, "  one dispatch per iteration (N = %d, timestamps between iterations): %.4f ms/iter"
                            " (p10 %.4f, p90 %.4f); first step with setup %.4f ms; a step past N %.4f ms\n",
                         s["n"].get<int>(), med(s["per_iteration_ms"]), s["per_iteration_ms"]["p10"].get<double>(),
                         s["per_iteration_ms"]["p90"].get<double>(), med(s["first_step_ms"]), med(s["pass_through_step_ms"]));
        }
    }
    if (b.contains("ilu_variants")) {
        const json& v = b["ilu_variants"];
        std::fprintf(f, "\n  ILU node's shaders at C = %lld, N = %d (GPU timestamps; wave 1 = the default's choice)\n",
                     v["C"].get<long long>(), v["iters"].get<int>());
        for (const json& r : v["rows"]) {
            if (r.contains("refused")) {
                std::fprintf(f, "    wave %4d  refused: %s\n", r["wave"].get<int>(), r["refused"].get<std::string>().c_str());
                continue;
            }
            std::fprintf(f, "    wave %4d  %-16s workgroup %4u  %.4f ms\n", r["wave"].get<int>(),
                         r.value("shader", std::string("?")).c_str(), r.value("workgroup", 0u), med(r["ms"]));
        }
    }
    if (b.contains("fps_variants")) {
        std::fprintf(f, "\n  FPS by workgroup size (GPU timestamps; threads 0 = the default's choice)\n");
        for (const json& r : b["fps_variants"]["rows"]) {
            std::fprintf(f, "    %5lld -> %4lld points, threads %4lld", r["points"].get<long long>(), r["npoint"].get<long long>(),
                         r["threads"].get<long long>());
            if (r.contains("refused")) std::fprintf(f, "  refused: %s\n", r["refused"].get<std::string>().c_str());
            else std::fprintf(f, "  %-13s workgroup %4u  %.4f ms\n", r.value("shader", std::string("?")).c_str(),
                              r.value("workgroup", 0u), med(r["ms"]));
        }
    }
    if (b.contains("retrieval_split")) {
        const json& s = b["retrieval_split"];
        const char* where = !s.contains("one_dispatch") ? "in the head node"
                            : s["one_dispatch"].get<bool>() ? "in the ILU's dispatch"
                                                            : "in the head node (two dispatches)";
        std::fprintf(f, "\n  retrieval %s: +%.4f ms (head %.4f ms with it, %.4f ms without);"
                        " as a node of its own %.4f ms\n",
                     where, s["epilogue_ms"].get<double>(), s["fused_head_ms"].get<double>(),
                     s["head_alone_ms"].get<double>(), s["node_ms"].get<double>());
    }
    if (b.contains("points")) {
        std::fprintf(f, "\n  point branch   encode ms (wall)   node sum ms   FPS ms   ball ms   MLP GFLOP/s\n");
        for (const json& r : b["points"])
            std::fprintf(f, "  %12lld %18.2f %13.2f %8.2f %9.2f %13.1f\n", r["points"].get<long long>(),
                         med(r["encode_ms"]), r["node_sum_ms"].get<double>(), r["fps_ms"].get<double>(),
                         r["ball_query_ms"].get<double>(), r["mlp"]["gflops"].get<double>());
    }
}

// The multi-touch filter's stage: per-touch medians on each backend, side by side.
void tracker(std::FILE* f, const json& t) {
    const json& any = t.contains("gpu") ? t["gpu"] : t["cpu"];
    std::fprintf(f, "\n== multi-touch filter (%s: %lld hypotheses = %lld samples x %d spins, %.2f mm apart; "
                 "window %d, touches %d..%d of %d timed, the tour continued by %s) ==\n",
                 any["object"].get<std::string>().c_str(), any["hypotheses"].get<long long>(), any["samples"].get<long long>(),
                 any["spins"].get<int>(), any["spacing_mm"].get<double>(), any["window"].get<int>(), any["window"].get<int>() + 1,
                 any["touches"].get<int>(), any["touches"].get<int>(),
                 any.contains("cycle") ? any["cycle"].get<std::string>().c_str() : "repeat");
    std::fprintf(f, "  %-16s %12s %12s %12s %10s %12s %10s\n", "backend", "touch (ms)", "add_touch", "estimate", "runs", "memory (MiB)",
                 "host (MiB)");
    for (const char* b : {"gpu", "cpu"}) {
        if (!t.contains(b)) continue;
        const json& x = t[b];
        const double host = x.contains("host_bytes") ? double(x["host_bytes"].get<uint64_t>()) / 1048576.0 : 0.0;
        std::fprintf(f, "  %-16s %12.2f %12.2f %12.2f %10d %12.1f %10.1f\n", b[0] == 'g' ? "GPU" : "CPU reference", med(x["touch_ms"]),
                     med(x["add_touch_ms"]), med(x["estimate_ms"]), x["reps"].get<int>(), double(x["device_bytes"].get<uint64_t>()) / 1048576.0,
                     host);
    }
    if (t.contains("cpu_over_gpu")) std::fprintf(f, "  CPU reference / GPU per touch: %.3gx\n", t["cpu_over_gpu"].get<double>());
    if (t.contains("gpu") && t["gpu"].contains("nodes_ms") && !t["gpu"]["nodes_ms"].empty()) {
        std::vector<std::pair<double, std::string>> nodes;  // slowest first
        for (const auto& [name, s] : t["gpu"]["nodes_ms"].items()) nodes.emplace_back(med(s), name);
        std::sort(nodes.rbegin(), nodes.rend());
        std::fprintf(f, "  a step's nodes (one profiled tracker, serial, medians):");
        for (const auto& [ms, name] : nodes) std::fprintf(f, " %s %.2f ms;", name.c_str(), ms);
        std::fprintf(f, "\n");
    }
    std::fprintf(f, "  surface built in %.0f ms (once per object)\n", any["surface_build_ms"].get<double>());
}

// The gel stage (SPEC 9): a frame's shape and one touch's render-and-compare.
void gel(std::FILE* f, const json& g) {
    std::fprintf(f, "\n== the gel's shape and render-and-compare (%s, %dx%d) ==\n", g["frame"].get<std::string>().c_str(),
                 g["size"][0].get<int>(), g["size"][1].get<int>());
    if (g.contains("shape_ms")) std::fprintf(f, "  shape of one frame, GPU      %10.2f ms\n", med(g["shape_ms"]));
    if (g.contains("shape_nodes_ms"))
        for (auto& [label, v] : g["shape_nodes_ms"].items()) std::fprintf(f, "    node %-22s %10.2f ms (GPU timestamps)\n", label.c_str(), med(v));
    std::fprintf(f, "  shape of one frame, CPU ref  %10.2f ms\n", med(g["shape_cpu_ms"]));
    // Both solves (50 sweeps from zeros, the coarse start) on this frame and on a rendered one.
    auto solves = [&](const char* what, const json& s) {
        for (const char* k : {"from_zeros", "coarse_start"})
            std::fprintf(f, "  %-10s %-12s%s %8.2f ms solve (GPU timestamps; frame %.2f ms wall, %lld contact pixels)\n", what, k,
                         s["uses"] == k ? "*" : " ", med(s[k]["solve_gpu_ms"]), med(s[k]["shape_ms"]), s[k]["mask_pixels"].get<long long>());
    };
    if (g.contains("solves")) solves("this frame", g["solves"]);  // *: the solve its reader uses
    if (g.contains("rendered")) solves("rendered", g["rendered"]);
    if (g.contains("codebook")) {
        const json& c = g["codebook"];
        std::fprintf(f, "  codebook of %s: %lld hypotheses, %lld dense points, rendered in %.0f ms (once per object)\n",
                     c["object"].get<std::string>().c_str(), c["hypotheses"].get<long long>(), c["dense_points"].get<long long>(),
                     c["render_ms"].get<double>());
        std::fprintf(f, "  one touch scored against it  %10.2f ms\n", med(c["score_ms"]));
    }
}

}  // namespace

void print_report(const json& r, std::FILE* f) {
    const json& d = r["device"];
    std::fprintf(f, "vtloc-bench  %s\n", r["date"].get<std::string>().c_str());
    std::fprintf(f, "device: %s (%s, driver %s, subgroup %d)\n", d["name"].get<std::string>().c_str(),
                 d["type"].get<std::string>().c_str(), d["driver_version"].get<std::string>().c_str(),
                 d["subgroup_size"].get<int>());
    if (r.contains("host")) {
        std::string simd;
        for (const json& s : r["host"]["simd"]) {
            if (!simd.empty()) simd += ' ';
            simd += s.get<std::string>();
        }
        std::fprintf(f, "host: %s, %d cores, SIMD: %s\n", r["host"]["cpu"].get<std::string>().c_str(),
                     r["host"]["cores"].get<int>(), simd.empty() ? "none listed" : simd.c_str());
        if (r["host"].contains("jit_override"))
            for (auto& [k, v] : r["host"]["jit_override"].items())
                std::fprintf(f, "      Mesa's JIT held by %s=%s (host_vector_registers %d)\n", k.c_str(),
                             v.get<std::string>().c_str(), r["device"].value("host_vector_registers", 0));
    }
    const json& m = r["model"];
    std::fprintf(f, "model: %s (%s): %lld parameters = %.2f MiB fp32\n", m["source"].get<std::string>().c_str(),
                 m["config_name"].get<std::string>().c_str(), m["parameters"].get<long long>(), m["mib_fp32"].get<double>());
    const json& in = r["inputs"];
    std::fprintf(f, "inputs: %s (%dx%d), %s (%lld points)\n", in["image"].get<std::string>().c_str(),
                 in["image_size"][0].get<int>(), in["image_size"][1].get<int>(), in["object"].get<std::string>().c_str(),
                 in["points"].get<long long>());
    if (r.contains("probe"))
        std::fprintf(f, "fma probe: %.1f GFLOP/s (higher of %.1f before and %.1f after); empty dispatch %.1f us\n",
                     r["probe"]["gflops"].get<double>(), r["probe"]["before"].get<double>(), r["probe"]["after"].get<double>(),
                     r["probe"]["dispatch_overhead_us"].get<double>());
    for (const char* b : {"gpu", "cpu"})
        if (r.contains(b)) backend(f, b, r[b]);
    if (r.contains("pytorch")) {
        const json& t = r["pytorch"];
        std::fprintf(f, "\n== PyTorch reference (torch %s, %s, %d threads, BLAS built %s, loaded %s) ==\n",
                     t["torch"].get<std::string>().c_str(), t["dtype"].get<std::string>().c_str(), t["threads"].get<int>(),
                     t["blas"]["built_with"].get<std::string>().c_str(), t["blas"]["loaded"].get<std::string>().c_str());
        std::fprintf(f, "  %-34s %9.2f ms\n", "end to end (one touch)", med(t["end_to_end_ms"]));
        for (auto& [k, v] : t["stages_ms"].items()) std::fprintf(f, "    %-12s %9.2f ms\n", k.c_str(), med(v));
        std::fprintf(f, "\n== engine / PyTorch (times, below 1 = the engine is faster) ==\n");
        for (auto& [k, v] : r["engine_over_pytorch"].items()) std::fprintf(f, "  %-20s %10.3g\n", k.c_str(), v.get<double>());
    }
    if (r.contains("tracker")) tracker(f, r["tracker"]);
    if (r.contains("gel")) gel(f, r["gel"]);
    if (r.contains("cpu_over_gpu")) {
        std::fprintf(f, "\n== CPU reference / GPU (times, higher = GPU faster) ==\n");
        for (auto& [k, v] : r["cpu_over_gpu"].items()) std::fprintf(f, "  %-20s %10.3gx\n", k.c_str(), v.get<double>());
    }
}

}  // namespace vtloc::bench
