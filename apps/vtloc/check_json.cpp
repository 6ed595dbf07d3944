// `vtloc check` results as JSON. Infinite errors (a wrong index, a NaN on one
// side) are written as null.
#include "apps/vtloc/check_json.h"

#include <cmath>

namespace vtloc::cli {

namespace {

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

nlohmann::json error_json(const api::CheckError& e) {
    nlohmann::json j{{"max_abs", number(e.max_abs)},
                     {"max_rel", number(e.max_rel)},
                     {"tolerance_used", number(e.tolerance_used)},
                     {"mismatches", e.mismatches}};
    if (e.has_indices) j["indices_equal"] = e.indices_equal;
    if (!e.first_mismatch.empty()) j["first_mismatch"] = e.first_mismatch;
    return j;
}

nlohmann::json device_json(const api::CheckDevice& d) {
    nlohmann::json limits = nlohmann::json::object();
    for (auto& [k, v] : d.limits) limits[k] = v;
    return {{"name", d.name}, {"type", d.type}, {"vulkan", d.vulkan}, {"driver", d.driver}, {"limits", limits}};
}

nlohmann::json tol_json(const api::CheckTolerance& t) { return {{"abs", t.abs}, {"rel", t.rel}}; }

nlohmann::json nodes_json(const std::vector<api::NodeCheck>& v) {
    nlohmann::json nodes = nlohmann::json::array();
    for (const api::NodeCheck& n : v) {
        nlohmann::json j{{"node", n.node},          {"op", n.op},
                         {"stage", n.stage},        {"ok", n.ok},
                         {"inputs", n.input_shapes}, {"outputs", n.output_shapes},
                         {"dispatches", n.dispatches}, {"error", error_json(n.error)}};
        if (!n.failure.empty()) j["failure"] = n.failure;
        nodes.push_back(std::move(j));
    }
    return nodes;
}

// A failing node's name, null if none.
nlohmann::json first_json(const std::vector<api::NodeCheck>& nodes, int i) {
    return i >= 0 ? nlohmann::json(nodes[size_t(i)].node) : nlohmann::json();
}

nlohmann::json outputs_json(const std::vector<api::OutputCheck>& v) {
    nlohmann::json outputs = nlohmann::json::array();
    for (const api::OutputCheck& out : v) outputs.push_back({{"name", out.name}, {"ok", out.ok}, {"error", error_json(out.error)}});
    return outputs;
}

}  // namespace

nlohmann::json check_json(const api::CheckResult& r, const api::CheckOptions& o) {
    const nlohmann::json nodes = nodes_json(r.nodes), outputs = outputs_json(r.outputs);
    nlohmann::json j{{"ok", r.ok},
                     {"model", o.model},
                     {"model_name", r.model_name},
                     {"tactile", o.tactile},
                     {"object", o.object},
                     {"device", device_json(r.device)},
                     {"tolerance", {{"node", tol_json(r.node_tolerance)}, {"end_to_end", tol_json(r.end_to_end_tolerance)}}},
                     {"nodes", nodes},
                     {"outputs", outputs},
                     {"ms", {{"gpu", r.gpu_ms}, {"cpu", r.cpu_ms}, {"wall", r.wall_ms}}}};
    j["first_failure"] = first_json(r.nodes, r.first_failure);
    return j;
}

nlohmann::json ops_check_json(const api::OpsCheckResult& r) {
    nlohmann::json cases = nlohmann::json::array();
    for (const api::OpCheck& c : r.cases) {
        nlohmann::json j{{"op", c.op},
                         {"variant", c.variant},
                         {"ok", c.ok},
                         {"tolerance", tol_json(c.tolerance)},
                         {"error", error_json(c.error)},
                         {"dispatches", c.dispatches},
                         {"ms", c.ms}};
        if (!c.failure.empty()) j["failure"] = c.failure;
        cases.push_back(std::move(j));
    }
    return {{"ok", r.ok},
            {"device", device_json(r.device)},
            {"cases", cases},
            {"uncovered_ops", r.uncovered_ops},
            {"ms", r.wall_ms}};
}

nlohmann::json tracker_check_json(const api::TrackerCheckResult& r, const api::TrackerCheckOptions& o) {
    nlohmann::json touches = nlohmann::json::array();
    for (const api::TouchCheck& t : r.touches)
        touches.push_back({{"touch", t.touch}, {"ok", t.ok}, {"belief", error_json(t.belief)}, {"contact_mm", number(t.contact_mm)}});
    nlohmann::json shape_terms = nlohmann::json::array();
    for (const api::ShapeTermCheck& t : r.shape_terms)
        shape_terms.push_back({{"frame", t.frame},
                               {"ok", t.ok},
                               {"shape", {{"nodes", nodes_json(t.shape_nodes)},
                                          {"outputs", outputs_json(t.shape_outputs)},
                                          {"first_failure", first_json(t.shape_nodes, t.first_failure)},
                                          {"depth", error_json(t.depth)},
                                          {"mask_pixels_differ", t.mask_pixels_differ}}},
                               {"term", error_json(t.term)}});
    nlohmann::json j{{"ok", r.ok},
                     {"touches_file", o.touches},
                     {"touch_terms", o.touch_terms},
                     {"shapes", o.shapes},
                     {"object", r.object},
                     {"hypotheses", r.hypotheses},
                     {"device", device_json(r.device)},
                     {"tolerance", {{"belief", tol_json(r.belief_tolerance)},
                                    {"node", tol_json(r.node_tolerance)},
                                    {"end_to_end", tol_json(r.end_to_end_tolerance)},
                                    {"term", tol_json(r.term_tolerance)},
                                    {"height", tol_json(r.height_tolerance)}}},
                     {"shape_terms", shape_terms},
                     {"touches", touches},
                     {"nodes", nodes_json(r.nodes)},
                     {"outputs", outputs_json(r.outputs)},
                     {"ms", {{"gpu", r.gpu_ms}, {"cpu", r.cpu_ms}, {"wall", r.wall_ms}}}};
    if (o.shapes)
        j["codebook"] = {{"cache", o.codebook_cache}, {"samples", r.codebook.samples}, {"checked", r.codebook.checked},
                         {"ok", r.codebook.ok}, {"heights", error_json(r.codebook.heights)}};
    j["first_failure"] = first_json(r.nodes, r.first_failure);
    // The step's first failing node, then the first frame's whose gel shape graph failed.
    nlohmann::json shape_failure;
    if (r.first_shape_failure >= 0) {
        const api::ShapeTermCheck& t = r.shape_terms[size_t(r.first_shape_failure)];
        shape_failure = {{"frame", t.frame}, {"node", first_json(t.shape_nodes, t.first_failure)}};
    }
    j["first_shape_failure"] = shape_failure;
    return j;
}

}  // namespace vtloc::cli
