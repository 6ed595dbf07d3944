// vtloc.check and vtloc.check_tracker: a device against the CPU reference (`vtloc check`), as dicts.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>

#include "python/arrays.h"

namespace vtloc::python {

namespace {

py::object number(double v) { return std::isfinite(v) ? py::object(py::float_(v)) : py::object(py::none()); }

py::dict error_dict(const api::CheckError& e) {
    py::dict d;
    d["max_abs"] = number(e.max_abs);
    d["max_rel"] = number(e.max_rel);
    d["tolerance_used"] = number(e.tolerance_used);
    d["mismatches"] = e.mismatches;
    if (e.has_indices) d["indices_equal"] = e.indices_equal;
    if (!e.first_mismatch.empty()) d["first_mismatch"] = e.first_mismatch;
    return d;
}

py::list nodes_list(const std::vector<api::NodeCheck>& v) {
    py::list out;
    for (const api::NodeCheck& n : v) {
        py::dict d;
        d["node"] = n.node, d["op"] = n.op, d["stage"] = n.stage, d["ok"] = n.ok;
        d["dispatches"] = n.dispatches, d["error"] = error_dict(n.error);
        if (!n.failure.empty()) d["failure"] = n.failure;
        out.append(d);
    }
    return out;
}

py::list outputs_list(const std::vector<api::OutputCheck>& v) {
    py::list out;
    for (const api::OutputCheck& o : v) {
        py::dict d;
        d["name"] = o.name, d["ok"] = o.ok, d["error"] = error_dict(o.error);
        out.append(d);
    }
    return out;
}

py::dict tol(const api::CheckTolerance& t) {
    py::dict d;
    d["abs"] = t.abs, d["rel"] = t.rel;
    return d;
}

py::object first(const std::vector<api::NodeCheck>& nodes, int i) {
    return i >= 0 ? py::object(py::str(nodes[size_t(i)].node)) : py::object(py::none());
}

}  // namespace

void bind_check(py::module_& m) {
    m.def(
        "check",
        [](api::Context& ctx, const std::string& model, const std::string& tactile, const std::string& object) {
            api::CheckResult r;
            {
                py::gil_scoped_release release;
                r = api::check(ctx, {model, tactile, object});
            }
            py::dict d;
            d["ok"] = r.ok, d["device"] = r.device.name, d["model_name"] = r.model_name;
            d["tolerance"] = py::dict(py::arg("node") = tol(r.node_tolerance), py::arg("end_to_end") = tol(r.end_to_end_tolerance));
            d["nodes"] = nodes_list(r.nodes), d["outputs"] = outputs_list(r.outputs);
            d["first_failure"] = first(r.nodes, r.first_failure);
            d["ms"] = py::dict(py::arg("gpu") = r.gpu_ms, py::arg("cpu") = r.cpu_ms, py::arg("wall") = r.wall_ms);
            return d;
        },
        py::arg("context"), py::arg("model"), py::arg("tactile"), py::arg("object"),
        "vtloc check: the model once on the device, every node against its CPU reference fed the GPU's inputs,\n"
        "the outputs against a full CPU run. -> dict: ok, nodes, outputs, first_failure, tolerance, ms.");
    m.def(
        "check_tracker",
        [](api::Context& ctx, const std::string& touches, const std::string& object, int64_t hypotheses, bool there_and_back,
           bool touch_terms, bool shapes, bool rendered_frames, const std::string& calibration, const std::string& background,
           const std::string& codebook_cache, int64_t codebook_samples) {
            api::TrackerCheckOptions o;
            o.touches = touches, o.object = object, o.hypotheses = hypotheses, o.there_and_back = there_and_back;
            o.touch_terms = touch_terms, o.shapes = shapes, o.codebook_cache = codebook_cache, o.codebook_samples = codebook_samples;
            o.rendered_frames = rendered_frames, o.calibration = calibration, o.background = background;
            api::TrackerCheckResult r;
            {
                py::gil_scoped_release release;
                r = api::check_tracker(ctx, o);
            }
            py::list ts;
            for (const api::TouchCheck& t : r.touches) {
                py::dict d;
                d["touch"] = t.touch, d["ok"] = t.ok, d["belief"] = error_dict(t.belief), d["contact_mm"] = number(t.contact_mm);
                ts.append(d);
            }
            py::dict d;
            d["ok"] = r.ok, d["device"] = r.device.name, d["object"] = r.object, d["hypotheses"] = r.hypotheses;
            d["tolerance"] = py::dict(py::arg("belief") = tol(r.belief_tolerance), py::arg("node") = tol(r.node_tolerance),
                                      py::arg("end_to_end") = tol(r.end_to_end_tolerance), py::arg("term") = tol(r.term_tolerance),
                                      py::arg("height") = tol(r.height_tolerance));
            py::list st;
            for (const api::ShapeTermCheck& t : r.shape_terms) {
                py::dict e;
                e["frame"] = t.frame, e["ok"] = t.ok, e["term"] = error_dict(t.term);
                e["shape"] = py::dict(py::arg("nodes") = nodes_list(t.shape_nodes), py::arg("outputs") = outputs_list(t.shape_outputs),
                                      py::arg("depth") = error_dict(t.depth), py::arg("mask_pixels_differ") = t.mask_pixels_differ,
                                      py::arg("first_failure") = first(t.shape_nodes, t.first_failure));
                st.append(e);
            }
            d["shape_terms"] = st;
            if (shapes) {
                py::dict c;
                c["cache"] = codebook_cache, c["samples"] = r.codebook.samples, c["checked"] = r.codebook.checked, c["ok"] = r.codebook.ok;
                c["heights"] = error_dict(r.codebook.heights);
                d["codebook"] = c;
            }
            d["touches"] = ts, d["nodes"] = nodes_list(r.nodes), d["outputs"] = outputs_list(r.outputs);
            d["first_failure"] = first(r.nodes, r.first_failure);
            py::object shape_failure = py::none();  // the first frame whose gel shape graph failed
            if (r.first_shape_failure >= 0) {
                const api::ShapeTermCheck& t = r.shape_terms[size_t(r.first_shape_failure)];
                shape_failure = py::dict(py::arg("frame") = t.frame, py::arg("node") = first(t.shape_nodes, t.first_failure));
            }
            d["first_shape_failure"] = shape_failure;
            d["ms"] = py::dict(py::arg("gpu") = r.gpu_ms, py::arg("cpu") = r.cpu_ms, py::arg("wall") = r.wall_ms);
            return d;
        },
        py::arg("context"), py::arg("touches"), py::arg("object") = "", py::arg("hypotheses") = 120000,
        py::arg("there_and_back") = true, py::arg("touch_terms") = false, py::arg("shapes") = false,
        py::arg("rendered_frames") = false, py::arg("calibration") = "", py::arg("background") = "",
        py::arg("codebook_cache") = "", py::arg("codebook_samples") = 0,
        "vtloc check --tracker: a GPU tracker and its CPU reference walk the touches file's tour (and back),\n"
        "beliefs compared after every touch, then the last step node by node. -> dict: ok, touches, nodes,\n"
        "outputs, first_failure, tolerance, ms. object: for a file without \"object\"; touch_terms: a seeded\n"
        "log term each touch, so the step reads a field per touch; shapes: each touch's frame read into its gel\n"
        "shape, the reader's graph checked node by node (shape_terms[i]['shape'], its first_failure; the first\n"
        "frame with one: first_shape_failure {frame, node}; rendered_frames, calibration,\n"
        "background: the reader's, as vtloc sequence takes them), then scored by render-and-compare on the device\n"
        "and the CPU reference (shape_terms), the device's term given to both,\n"
        "and the codebook's maps (codebook_cache's, or the device's render) against the CPU reference's render at\n"
        "codebook_samples samples spread over it (0: all; codebook: samples, checked, ok, heights).");
}

}  // namespace vtloc::python
