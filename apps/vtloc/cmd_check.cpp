// vtloc check: can this device be trusted? The model (or, with --ops, every
// op) on the Vulkan device against the CPU reference.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>

#include "apps/vtloc/check_json.h"
#include "apps/vtloc/check_print.h"
#include "apps/vtloc/check_tracker.h"
#include "apps/vtloc/cli.h"
#include "base/atomic_write.h"

namespace vtloc::cli {

namespace fs = std::filesystem;

namespace {

const char* kHelp =
    "usage: vtloc check [--model M] [--tactile IMG --object OBJ] [--device D] [--json FILE] [--verbose]\n"
    "       vtloc check --ops [--op NAME] [--device D] [--json FILE] [--verbose]\n"
    "       vtloc check --tracker [--touches SEQ.json] [--object OBJ] [--hypotheses N] [--one-way] [--terms | --shapes]\n"
    "                   [--rendered] [--calibration C] [--background BG] [--codebook-cache F] [--codebook-samples N]\n"
    "                   [--device D] [--json FILE] [--verbose]\n"
    "\n"
    "Cross-checks the Vulkan device against the engine's CPU reference.\n"
    "\n"
    "Model check (default): runs the model once on the device keeping every intermediate,\n"
    "then runs each node's CPU reference on the GPU's own inputs to that node (errors do\n"
    "not accumulate; index ops compare exactly), and the whole model on the CPU for the\n"
    "end-to-end outputs. Prints a table per stage and the first node out of tolerance\n"
    "with its op, shapes and shader specialization constants. Tolerances:\n"
    "  per node     |gpu - cpu| <= 1e-4 + 1e-4*|cpu|, index outputs exactly\n"
    "  end to end   |gpu - cpu| <= 2e-3 + 2e-3*|cpu|\n"
    "\n"
    "  --model M     weight file (default: the shipped model)\n"
    "  --tactile IMG tactile image and --object OBJ mesh or PLY cloud (default: the\n"
    "  --object OBJ  shipped example, examples/touch_01.png on examples/mug.glb)\n"
    "  --ops         the built-in op self-test instead: every registered op at odd shapes\n"
    "                and on each variant (texel / storage-buffer paths, the tile shapes\n"
    "                this device's limits choose)\n"
    "  --op NAME     with --ops: only ops whose name contains NAME\n"
    "  --tracker     the multi-touch filter instead: a GPU tracker and its CPU reference twin\n"
    "                walk the touches file's tour (default: the shipped potato tour) and back\n"
    "                over it in reverse (past the window: the prior's path; --one-way: not), their\n"
    "                beliefs compared after every touch (|gpu - cpu| <= 1e-6 * peak +\n"
    "                5e-3*|cpu|), then the last touch's step node by node as above, at the\n"
    "                object's full size (--hypotheses, default 120000: the tables' sizes pick\n"
    "                the shader paths); --object OBJ for a file without \"object\"; --terms:\n"
    "                each touch also carries a seeded log term over the hypotheses (as\n"
    "                render-and-compare's would), so the step reads a field per touch;\n"
    "                --shapes: each touch's own frame read into its gel shape, the reader's\n"
    "                graph checked node by node on it (--rendered: the reader for frames vtloc\n"
    "                synth rendered; --calibration C, --background BG as vtloc sequence takes\n"
    "                them), then scored against the object's codebook (render-and-compare's\n"
    "                term) on the device and by the CPU reference scorer, compared per frame,\n"
    "                the device's term given to both trackers; and the codebook's maps (the\n"
    "                device's render, or --codebook-cache F's, read or written as the tracker\n"
    "                would) against the CPU reference's render at --codebook-samples N samples\n"
    "                spread over it (default 0: all), exactly\n"
    "  --device D    device index or name substring (default: VTLOC_DEVICE, else the best)\n"
    "  --json FILE   also write the full result (every node / case) as JSON\n"
    "  --verbose     every node (model check) / every dispatch (--ops, --tracker)\n"
    "\n"
    "Exit status 0 when everything is within tolerance, 1 on any mismatch (or bad input).\n";

int model_check(Session& s, const Args& a) {
    api::CheckOptions o;
    const bool tactile = a.get("--tactile").has_value(), object = a.get("--object").has_value();
    if (tactile != object) throw UsageError("--tactile and --object go together");
    o.model = a.get("--model") ? *a.get("--model") : default_model_path();
    o.tactile = tactile ? *a.get("--tactile") : (shipped_dir() / "examples" / "touch_01.png").string();
    o.object = object ? *a.get("--object") : (shipped_dir() / "examples" / "mug.glb").string();
    std::printf("check      %s on %s + %s\n", o.model.c_str(), o.tactile.c_str(), o.object.c_str());
    std::fflush(stdout);
    api::CheckResult r = api::check(s.gpu(), o);
    print_device(r.device, false);
    std::printf("tolerance  per node |gpu - cpu| <= %g + %g*|cpu| (each CPU node fed the GPU's inputs), indices exact\n",
                r.node_tolerance.abs, r.node_tolerance.rel);
    std::printf("           end to end |gpu - cpu| <= %g + %g*|cpu| (outputs against a full CPU run)\n\n",
                r.end_to_end_tolerance.abs, r.end_to_end_tolerance.rel);

    struct Stage { size_t nodes = 0, bad = 0; api::CheckError e; std::vector<std::string> ops; };
    std::vector<std::pair<std::string, Stage>> stages;
    for (const api::NodeCheck& n : r.nodes) {
        if (stages.empty() || stages.back().first != n.stage) stages.push_back({n.stage, {}});
        Stage& st = stages.back().second;
        ++st.nodes;
        st.bad += !n.ok;
        st.e.max_abs = std::max(st.e.max_abs, n.error.max_abs);
        st.e.max_rel = std::max(st.e.max_rel, n.error.max_rel);
        st.e.tolerance_used = std::max(st.e.tolerance_used, n.error.tolerance_used);
        st.e.has_indices = st.e.has_indices || n.error.has_indices;
        st.e.indices_equal = st.e.indices_equal && n.error.indices_equal;
    }
    const bool verbose = a.flag("--verbose");
    std::printf("%-24s %5s  %-9s %-9s %-8s %-7s %s\n", "stage", "nodes", "max abs", "max rel", "tol used", "indices",
                "result");
    for (auto& [name, st] : stages)
        std::printf("%-24s %5zu  %-9s %-9s %-8s %-7s %s\n", name.c_str(), st.nodes, g3(st.e.max_abs).c_str(),
                    g3(st.e.max_rel).c_str(), g3(st.e.tolerance_used).c_str(), indices_str(st.e).c_str(),
                    st.bad ? (std::to_string(st.bad) + " FAILED").c_str() : "ok");
    if (verbose) {
        std::printf("\n%-40s %-18s %-9s %-9s %-7s %s\n", "node", "op", "max abs", "max rel", "indices", "result");
        for (const api::NodeCheck& n : r.nodes)
            std::printf("%-40s %-18s %-9s %-9s %-7s %s\n", n.node.c_str(), n.op.c_str(), g3(n.error.max_abs).c_str(),
                        g3(n.error.max_rel).c_str(), indices_str(n.error).c_str(), n.ok ? "ok" : "FAILED");
    }
    std::printf("\n%-24s %5s  %-9s %-9s %-8s %-7s %s\n", "end to end (output)", "", "max abs", "max rel", "tol used",
                "indices", "result");
    size_t bad_outputs = 0;
    for (const api::OutputCheck& out : r.outputs) {
        bad_outputs += !out.ok;
        std::printf("%-24s %5s  %-9s %-9s %-8s %-7s %s\n", out.name.c_str(), "", g3(out.error.max_abs).c_str(),
                    g3(out.error.max_rel).c_str(), g3(out.error.tolerance_used).c_str(), indices_str(out.error).c_str(),
                    out.ok ? "ok" : ("FAILED (" + out.error.first_mismatch + ")").c_str());
    }
    if (r.first_failure >= 0) {
        std::printf("\nfirst node out of tolerance:\n");
        print_node(r.nodes[size_t(r.first_failure)]);
    }
    size_t bad_nodes = 0;
    for (const api::NodeCheck& n : r.nodes) bad_nodes += !n.ok;
    std::printf("\n%s: %zu of %zu nodes and %zu of %zu outputs within tolerance (GPU run %.0f ms, CPU reference "
                "%.0f ms, total %.1f s)\n",
                r.ok ? "OK" : "FAILED", r.nodes.size() - bad_nodes, r.nodes.size(), r.outputs.size() - bad_outputs,
                r.outputs.size(), r.gpu_ms, r.cpu_ms, r.wall_ms / 1000.0);
    if (a.get("--json")) write_json(*a.get("--json"), check_json(r, o));
    if (r.ok) return 0;
    std::fflush(stdout);
    if (r.first_failure >= 0) {
        const api::NodeCheck& n = r.nodes[size_t(r.first_failure)];
        std::fprintf(stderr, "vtloc: check failed on %s: node '%s' (%s) differs from the CPU reference\n",
                     r.device.name.c_str(), n.node.c_str(), n.op.c_str());
    } else {
        std::fprintf(stderr, "vtloc: check failed on %s: the end-to-end outputs differ from the CPU reference\n",
                     r.device.name.c_str());
    }
    return 1;
}

int ops_check(Session& s, const Args& a) {
    const bool verbose = a.flag("--verbose");
    api::Context& ctx = s.gpu();
    std::printf("check      every registered op against its CPU reference (built-in self-test)\n");
    std::printf("%-20s %-70s %-9s %-8s %s\n", "op", "variant", "max abs", "ms", "result");
    std::fflush(stdout);
    auto progress = [&](size_t, size_t, const api::OpCheck& c) {
        std::printf("%-20s %-70s %-9s %-8.0f %s\n", c.op.c_str(), c.variant.c_str(), g3(c.error.max_abs).c_str(), c.ms,
                    c.ok ? "ok" : "FAILED");
        if (verbose || !c.ok)
            for (const std::string& d : c.dispatches) std::printf("    dispatch %s\n", d.c_str());
        if (!c.failure.empty()) std::printf("    error: %s\n", c.failure.c_str());
        if (!c.error.first_mismatch.empty()) std::printf("    mismatch: %s\n", c.error.first_mismatch.c_str());
        std::fflush(stdout);
    };
    api::OpsCheckResult r = api::check_ops(ctx, a.get("--op").value_or(""), progress);
    for (const std::string& op : r.uncovered_ops)
        std::printf("%-20s %-70s %-9s %-8s %s\n", op.c_str(), "(no self-test case)", "-", "-", "FAILED");
    std::printf("\n");
    print_device(r.device, true);
    std::map<std::string, bool> ops;
    size_t bad = 0;
    for (const api::OpCheck& c : r.cases) {
        ops[c.op] = ops.count(c.op) ? ops[c.op] && c.ok : c.ok;
        bad += !c.ok;
    }
    std::printf("\n%s: %zu ops, %zu of %zu cases within tolerance%s (%.1f s)\n", r.ok ? "OK" : "FAILED", ops.size(),
                r.cases.size() - bad, r.cases.size(),
                r.uncovered_ops.empty() ? "" : (", " + std::to_string(r.uncovered_ops.size()) + " ops with no case").c_str(),
                r.wall_ms / 1000.0);
    if (a.get("--json")) write_json(*a.get("--json"), ops_check_json(r));
    if (r.ok) return 0;
    std::fflush(stdout);
    std::fprintf(stderr, "vtloc: op self-test failed on %s: %zu cases out of tolerance, %zu ops without a case\n",
                 r.device.name.c_str(), bad, r.uncovered_ops.size());
    return 1;
}

}  // namespace

int cmd_check(Session& s, int argc, char** argv) {
    Args a(argc, argv, 2,
           {{"--model"}, {"--tactile"}, {"--object"}, {"--device"}, {"--json"}, {"--ops", false}, {"--op"},
            {"--verbose", false}, {"--tracker", false}, {"--touches"}, {"--hypotheses"}, {"--object-units"},
            {"--one-way", false}, {"--terms", false}, {"--shapes", false}, {"--codebook-cache"}, {"--codebook-samples"},
            {"--rendered", false}, {"--calibration"}, {"--background"}});
    if (a.help()) {
        std::fputs(kHelp, stdout);
        return 0;
    }
    const bool ops = a.flag("--ops"), tracker = a.flag("--tracker");
    if (ops && tracker) throw UsageError("--ops and --tracker are two checks: one at a time");
    if (ops && (a.get("--model") || a.get("--tactile") || a.get("--object")))
        throw UsageError("--ops takes no --model, --tactile or --object");
    if (tracker && (a.get("--model") || a.get("--tactile")))
        throw UsageError("--tracker takes no --model or --tactile (the touches file names the frames)");
    for (const char* opt : {"--touches", "--hypotheses", "--object-units", "--one-way", "--terms", "--shapes"})
        if (!tracker && a.get(opt)) throw UsageError(std::string(opt) + " needs --tracker");
    for (const char* opt : {"--codebook-cache", "--codebook-samples", "--rendered", "--calibration", "--background"})
        if (!a.flag("--shapes") && a.get(opt)) throw UsageError(std::string(opt) + " needs --tracker --shapes");
    if (!ops && a.get("--op")) throw UsageError("--op needs --ops");
    if (a.get("--device")) s.context.emplace(api::ContextOptions{*a.get("--device")});
    return ops ? ops_check(s, a) : tracker ? tracker_check(s, a) : model_check(s, a);
}

}  // namespace vtloc::cli
