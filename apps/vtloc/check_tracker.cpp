#include "apps/vtloc/check_tracker.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>

#include "apps/vtloc/check_json.h"
#include "apps/vtloc/check_print.h"

namespace vtloc::cli {

namespace {

// One row of a node or output table: label, op, the error's columns, the result.
void print_row(const std::string& label, const std::string& op, const api::CheckError& e, bool ok, const std::string& failed) {
    std::printf("%-40s %-18s %-9s %-9s %-8s %s\n", label.c_str(), op.c_str(), g3(e.max_abs).c_str(), g3(e.max_rel).c_str(),
                g3(e.tolerance_used).c_str(), ok ? "ok" : failed.c_str());
}

}  // namespace

int tracker_check(Session& s, const Args& a) {
    api::TrackerCheckOptions o;
    o.touches = a.get("--touches").value_or((shipped_dir() / "examples" / "potato_tour.json").string());
    o.object = a.get("--object").value_or("");
    o.hypotheses = a.integer("--hypotheses", int(o.hypotheses), 100, 2000000);
    o.object_units = a.number("--object-units", 1.0);
    o.there_and_back = !a.flag("--one-way");
    o.touch_terms = a.flag("--terms");
    o.shapes = a.flag("--shapes");
    o.codebook_cache = a.get("--codebook-cache").value_or("");
    o.rendered_frames = a.flag("--rendered");
    o.calibration = a.get("--calibration").value_or("");
    o.background = a.get("--background").value_or("");
    o.codebook_samples = a.integer("--codebook-samples", int(o.codebook_samples), 0, 100000000);
    std::printf("check      the multi-touch filter on %s (%s)%s%s\n", o.touches.c_str(),
                o.object.empty() ? "the file's object" : o.object.c_str(), o.there_and_back ? ", there and back" : "",
                o.touch_terms ? ", a seeded term each touch" : o.shapes ? ", render-and-compare of each touch's frame" : "");
    std::fflush(stdout);
    const api::TrackerCheckResult r = api::check_tracker(s.gpu(), o);
    print_device(r.device, false);
    std::printf("object     %s: %lld hypotheses\n", r.object.c_str(), (long long)r.hypotheses);
    std::printf("tolerance  belief after each touch |gpu - cpu| <= %g * (the reference's peak) + %g*|cpu|\n",
                r.belief_tolerance.abs, r.belief_tolerance.rel);
    std::printf("           the last step per node |gpu - cpu| <= %g + %g*|cpu| (each CPU node fed the GPU's inputs)\n",
                r.node_tolerance.abs, r.node_tolerance.rel);
    std::printf("           its outputs |gpu - cpu| <= %g + %g*|cpu| (against a full CPU run)\n", r.end_to_end_tolerance.abs,
                r.end_to_end_tolerance.rel);
    size_t bad_terms = 0;
    if (!r.shape_terms.empty()) {
        std::printf("           each frame's gel shape: the reader's graph per node and end to end, as above, and\n"
                    "           the shape it read against the CPU reference run's (depth mm as end to end, the contact exactly)\n");
        std::printf("           render-and-compare's term |gpu - cpu| <= %g + %g*|cpu| (the CPU reference scorer)\n\n",
                    r.term_tolerance.abs, r.term_tolerance.rel);
        std::printf("%-28s %-18s %-10s %-9s %-9s %-8s %s\n", "frame", "shape: nodes, outs", "depth abs", "term abs", "term rel",
                    "tol used", "result");
        for (const api::ShapeTermCheck& t : r.shape_terms) {
            bad_terms += !t.ok;
            const std::string name = std::filesystem::path(t.frame).filename().string();
            size_t nodes_ok = 0, outs_ok = 0;
            for (const api::NodeCheck& n : t.shape_nodes) nodes_ok += n.ok;
            for (const api::OutputCheck& o : t.shape_outputs) outs_ok += o.ok;
            const std::string shape = std::to_string(nodes_ok) + "/" + std::to_string(t.shape_nodes.size()) + ", " +
                                      std::to_string(outs_ok) + "/" + std::to_string(t.shape_outputs.size());
            const bool term_ok = t.term.mismatches == 0, read_ok = t.depth.mismatches == 0 && t.mask_pixels_differ == 0;
            const std::string why = !read_ok ? "FAILED (the shape read: " + std::to_string(t.depth.mismatches) + " depths, " +
                                                   std::to_string(t.mask_pixels_differ) + " contact pixels differ)"
                                    : !term_ok ? "FAILED (" + t.term.first_mismatch + ")"
                                               : "FAILED (its shape's graph)";
            std::printf("%-28s %-18s %-10s %-9s %-9s %-8s %s\n", name.c_str(), shape.c_str(), g3(t.depth.max_abs).c_str(),
                        g3(t.term.max_abs).c_str(), g3(t.term.max_rel).c_str(), g3(t.term.tolerance_used).c_str(),
                        t.ok ? "ok" : why.c_str());
            for (const api::NodeCheck& n : t.shape_nodes)
                if (!n.ok || a.flag("--verbose"))
                    print_row("    node " + n.node, n.op, n.error, n.ok, "FAILED (" + n.error.first_mismatch + n.failure + ")");
            for (const api::OutputCheck& o : t.shape_outputs)
                if (!o.ok || a.flag("--verbose"))
                    print_row("    output " + o.name, "", o.error, o.ok, "FAILED (" + o.error.first_mismatch + ")");
        }
        const api::CodebookCheck& c = r.codebook;
        std::printf("\ncodebook   %s: %lld of %lld samples' maps against the CPU reference's render, heights exactly: %s\n",
                    o.codebook_cache.empty() ? "rendered on the device" : o.codebook_cache.c_str(), (long long)c.checked,
                    (long long)c.samples, c.ok ? "ok" : ("FAILED (" + std::to_string(c.heights.mismatches) + " cells differ; " +
                                                          c.heights.first_mismatch + ")").c_str());
    }
    std::printf("\n%-6s %-9s %-9s %-8s %-12s %s\n", "touch", "max abs", "max rel", "tol used", "contacts mm", "result");
    size_t bad_touches = 0;
    for (const api::TouchCheck& t : r.touches) {
        bad_touches += !t.ok;
        std::printf("%-6d %-9s %-9s %-8s %-12.4f %s\n", t.touch, g3(t.belief.max_abs).c_str(), g3(t.belief.max_rel).c_str(),
                    g3(t.belief.tolerance_used).c_str(), t.contact_mm,
                    t.ok ? "ok" : ("FAILED (" + t.belief.first_mismatch + ")").c_str());
    }
    std::printf("\n%-40s %-18s %-9s %-9s %-8s %s\n", "the last touch's step: node", "op", "max abs", "max rel", "tol used",
                "result");
    size_t bad_nodes = 0;
    for (const api::NodeCheck& n : r.nodes) {
        bad_nodes += !n.ok;
        print_row(n.node, n.op, n.error, n.ok, "FAILED");
        if (a.flag("--verbose"))
            for (const std::string& d : n.dispatches) std::printf("    dispatch %s\n", d.c_str());
    }
    size_t bad_outputs = 0;
    for (const api::OutputCheck& out : r.outputs) {
        bad_outputs += !out.ok;
        print_row("output " + out.name, "", out.error, out.ok, "FAILED (" + out.error.first_mismatch + ")");
    }
    if (r.first_failure >= 0) {
        std::printf("\nfirst node out of tolerance:\n");
        print_node(r.nodes[size_t(r.first_failure)]);
    }
    if (r.first_shape_failure >= 0) {  // and the first frame's whose shape graph failed
        const api::ShapeTermCheck& t = r.shape_terms[size_t(r.first_shape_failure)];
        std::printf("\nfirst gel shape node out of tolerance (%s):\n", std::filesystem::path(t.frame).filename().string().c_str());
        print_node(t.shape_nodes[size_t(t.first_failure)]);
    }
    const std::string frames = r.shape_terms.empty() ? "" : std::string(r.codebook.ok ? "the codebook, " : "") +
                                                                 std::to_string(r.shape_terms.size() - bad_terms) + " of " +
                                                                 std::to_string(r.shape_terms.size()) + " frames' shapes and terms, ";
    std::printf("\n%s: %s%zu of %zu touches' beliefs, %zu of %zu nodes and %zu of %zu outputs within tolerance (GPU %.0f ms, "
                "CPU reference %.0f ms, total %.1f s)\n",
                r.ok ? "OK" : "FAILED", frames.c_str(), r.touches.size() - bad_touches, r.touches.size(), r.nodes.size() - bad_nodes,
                r.nodes.size(), r.outputs.size() - bad_outputs, r.outputs.size(), r.gpu_ms, r.cpu_ms, r.wall_ms / 1000.0);
    if (a.get("--json")) write_json(*a.get("--json"), tracker_check_json(r, o));
    if (r.ok) return 0;
    std::fflush(stdout);
    std::fprintf(stderr, "vtloc: tracker check failed on %s: %s%zu frames' shapes or terms, %zu touches' beliefs, %zu nodes, %zu outputs differ from the CPU reference\n",
                 r.device.name.c_str(), r.codebook.ok ? "" : "the codebook's maps, ", bad_terms, bad_touches, bad_nodes, bad_outputs);
    return 1;
}

}  // namespace vtloc::cli
