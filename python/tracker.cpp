// vtloc.Tracker: the multi-touch filter (SPEC section 6), numpy in and out.
// Motions and poses are 4 x 4 homogeneous float arrays (the rotation in the
// upper left, the translation in the last column, object units).
#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>
#include <type_traits>
#include <variant>

#include <pybind11/stl.h>

#include "arrays.h"

namespace vtloc::python {

namespace {

api::Motion to_motion(const py::handle& obj, const std::string& what) {
    py::array a = py::array::ensure(obj);
    if (!a || a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4 ||
        !(a.dtype().is(py::dtype::of<float>()) || a.dtype().is(py::dtype::of<double>())))
        throw api::Error(what + ": expected a float32 or float64 4 x 4 array, got " + (a ? describe(a) : "something else"));
    py::array_t<double, py::array::c_style | py::array::forcecast> d(a);
    auto r = d.unchecked<2>();
    for (int i = 0; i < 4; ++i)  // first, so that a NaN in the last row is named as one
        for (int j = 0; j < 4; ++j)
            if (!std::isfinite(r(i, j)))
                throw api::Error(what + ": row " + std::to_string(i) + ", column " + std::to_string(j) + " holds NaN or inf");
    for (int i = 0; i < 3; ++i)
        if (r(3, i) != 0) throw api::Error(what + ": the last row must be 0 0 0 1");
    if (r(3, 3) != 1) throw api::Error(what + ": the last row must be 0 0 0 1");
    api::Motion m;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) m.R[size_t(i * 3 + j)] = r(i, j);
        m.t[size_t(i)] = r(i, 3);
    }
    return m;
}

py::array_t<double> matrix(const api::Motion& m) {
    py::array_t<double> a({4, 4});
    auto r = a.mutable_unchecked<2>();
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r(i, j) = i == 3 ? (j == 3 ? 1.0 : 0.0) : j == 3 ? m.t[size_t(i)] : m.R[size_t(i * 3 + j)];
    return a;
}

api::TrackerOptions options(double press_mm, double sigma_d_mm, double sigma_a_deg, double odometry_mm, double odometry_deg,
                            int window, int n_spin, int64_t hypotheses, double network_weight, double object_units) {
    api::TrackerOptions o;
    o.press_mm = press_mm, o.sigma_d_mm = sigma_d_mm, o.sigma_a_deg = sigma_a_deg;
    o.odometry_mm = odometry_mm, o.odometry_deg = odometry_deg, o.window = window, o.n_spin = n_spin;
    o.hypotheses = hypotheses, o.network_weight = network_weight, o.object_units = object_units;
    return o;
}

// A gel shape as GelShapeReader.read returns it: a dict with depth_mm (H x W, mm) and mm_per_px.
api::GelShape to_shape(const py::object& o) {
    if (!py::isinstance<py::dict>(o)) throw api::Error("shape: expected GelShapeReader.read's dict (depth_mm, mm_per_px)");
    const py::dict d = o.cast<py::dict>();
    if (!d.contains("depth_mm") || !d.contains("mm_per_px")) throw api::Error("shape: the dict needs depth_mm and mm_per_px");
    const auto a = d["depth_mm"].cast<py::array_t<float, py::array::c_style | py::array::forcecast>>();
    if (a.ndim() != 2) throw api::Error("shape: depth_mm must be an H x W array");
    api::GelShape s;
    s.height = int(a.shape(0)), s.width = int(a.shape(1));
    s.mm_per_px = d["mm_per_px"].cast<double>();
    s.depth_mm.assign(a.data(), a.data() + a.size());
    return s;
}

py::dict estimate_dict(const api::TrackerEstimate& e) {
    py::dict d;
    d["touches"] = e.touches;
    d["contact"] = vec3(e.contact);
    d["pose"] = matrix(e.pose);
    d["pose_contact"] = vec3(e.pose_contact);
    py::list w;
    for (const api::Motion& m : e.window_poses) w.append(matrix(m));
    d["window_poses"] = w;
    py::list modes;
    for (const api::TrackerMode& m : e.modes) modes.append(py::make_tuple(vec3(m.contact), m.probability));
    d["modes"] = modes;
    d["mass_within_5mm"] = e.mass_within_5mm;
    d["fit"] = e.fit;
    d["pose_terms"] = e.pose_terms;
    d["heatmap"] = floats(e.heatmap);
    d["sample_belief"] = floats(e.sample_belief);
    return d;
}

// Every option but candidates, once: Tracker.options reads this table and with_options writes it.
using Member = std::variant<double api::TrackerOptions::*, int api::TrackerOptions::*, int64_t api::TrackerOptions::*,
                            bool api::TrackerOptions::*, std::string api::TrackerOptions::*>;
struct NamedOption {
    const char* name;
    Member member;
};
#define VTLOC_OPTION(n) NamedOption{#n, &api::TrackerOptions::n}
const NamedOption kOptions[] = {
    VTLOC_OPTION(press_mm), VTLOC_OPTION(sigma_d_mm), VTLOC_OPTION(sigma_a_deg), VTLOC_OPTION(odometry_mm),
    VTLOC_OPTION(odometry_deg), VTLOC_OPTION(window), VTLOC_OPTION(n_spin), VTLOC_OPTION(hypotheses),
    VTLOC_OPTION(network_weight), VTLOC_OPTION(object_units), VTLOC_OPTION(render_weight),
    VTLOC_OPTION(render_quadratic), VTLOC_OPTION(render_press_percentile), VTLOC_OPTION(render_cell_mm),
    VTLOC_OPTION(render_refined_weight), VTLOC_OPTION(render_refined_floor), VTLOC_OPTION(render_slack_rounds),
    VTLOC_OPTION(field_slack), VTLOC_OPTION(codebook_cache), VTLOC_OPTION(threads), VTLOC_OPTION(free_space_mm),
    VTLOC_OPTION(free_space_w_mm), VTLOC_OPTION(free_space_h_mm), VTLOC_OPTION(mode_radius_mm),
    VTLOC_OPTION(grid_allowance), VTLOC_OPTION(refine_widen), VTLOC_OPTION(refine_reach_mm),
    VTLOC_OPTION(rescue_fit), VTLOC_OPTION(rescue_modes), VTLOC_OPTION(register_rounds), VTLOC_OPTION(deep_fit),
    VTLOC_OPTION(deep_modes),
    VTLOC_OPTION(pair_modes), VTLOC_OPTION(profile),
};
#undef VTLOC_OPTION

py::dict options_dict(const api::TrackerOptions& o) {
    py::dict d;
    for (const NamedOption& n : kOptions) std::visit([&](auto m) { d[n.name] = o.*m; }, n.member);
    if (o.candidates.empty()) {
        d["candidates"] = py::none();
    } else {
        py::array_t<double> c({py::ssize_t(o.candidates.size()), py::ssize_t(3)});
        auto r = c.mutable_unchecked<2>();
        for (size_t i = 0; i < o.candidates.size(); ++i)
            for (int k = 0; k < 3; ++k) r(py::ssize_t(i), k) = o.candidates[i][size_t(k)];
        d["candidates"] = c;
    }
    return d;
}

const char* kTrackerDoc =
    "The multi-touch filter (SPEC section 6): a belief over sensor poses on the object's surface.\n"
    "Tracker(context, object) with object a mesh or cloud path, or an N x 6 array (points and\n"
    "normals, object units). add_touch(motion=None, result=None, object=None): the first touch\n"
    "takes no motion, each later one the 4 x 4 motion from the previous touch (pose b in pose a's\n"
    "frame); result: that touch's TouchResult on `object` (a network term); shape: its gel's shape\n"
    "(GelShapeReader.read's dict: render-and-compare, SPEC 9). estimate() -> dict.\n"
    "candidates: a C x 3 array: hypotheses only at these points (the paper's candidates protocol).";

}  // namespace

void bind_tracker(py::module_& m) {
    py::class_<api::Tracker>(m, "Tracker", kTrackerDoc)
        .def(py::init([](api::Context& ctx, const py::object& object, double press_mm, double sigma_d_mm, double sigma_a_deg,
                         double odometry_mm, double odometry_deg, int window, int n_spin, int64_t hypotheses,
                         double network_weight, double object_units, const py::object& candidates, double render_weight,
                         const std::string& codebook_cache, bool render_quadratic, double render_press_percentile,
                         double render_cell_mm, int threads, double free_space_mm, double render_refined_weight,
                         int render_slack_rounds, bool field_slack, double render_refined_floor, bool profile) {
                 api::TrackerOptions o = options(press_mm, sigma_d_mm, sigma_a_deg, odometry_mm, odometry_deg, window,
                                                 n_spin, hypotheses, network_weight, object_units);
                 o.render_weight = render_weight, o.codebook_cache = codebook_cache, o.render_quadratic = render_quadratic;
                 o.render_press_percentile = render_press_percentile, o.render_cell_mm = render_cell_mm;
                 o.threads = threads, o.free_space_mm = free_space_mm, o.render_refined_weight = render_refined_weight;
                 o.render_slack_rounds = render_slack_rounds, o.field_slack = field_slack;
                 o.render_refined_floor = render_refined_floor, o.profile = profile;
                 if (!candidates.is_none()) {  // C x 3, the candidates protocol
                     const auto c = candidates.cast<py::array_t<double, py::array::c_style | py::array::forcecast>>();
                     if (c.ndim() != 2 || c.shape(1) != 3)
                         throw api::Error("candidates: expected a C x 3 array of contact points");
                     const auto r = c.unchecked<2>();
                     for (py::ssize_t i = 0; i < c.shape(0); ++i) o.candidates.push_back({r(i, 0), r(i, 1), r(i, 2)});
                 }
                 // The surface's build (up to a second) runs without the GIL, as every call does that
                 // works or waits for the tracker's lock.
                 if (py::isinstance<py::str>(object)) {
                     const std::string path = object.cast<std::string>();
                     py::gil_scoped_release release;
                     return api::Tracker(ctx, path, o);
                 }
                 api::PointCloud c = to_cloud(object, "object");
                 for (float& v : c.xyz) v = float(v * object_units);
                 py::gil_scoped_release release;
                 return api::Tracker(ctx, c, o);
             }),
             py::arg("context"), py::arg("object"), py::arg("press_mm") = 0.8, py::arg("sigma_d_mm") = 1.0,
             py::arg("sigma_a_deg") = 6.0, py::arg("odometry_mm") = 0.0, py::arg("odometry_deg") = 0.0, py::arg("window") = 8,
             py::arg("n_spin") = 36, py::arg("hypotheses") = 120000, py::arg("network_weight") = 0.5,
             py::arg("object_units") = 1.0, py::arg("candidates") = py::none(), py::arg("render_weight") = api::TrackerOptions{}.render_weight,
             py::arg("codebook_cache") = "", py::arg("render_quadratic") = api::TrackerOptions{}.render_quadratic,
             py::arg("render_press_percentile") = api::TrackerOptions{}.render_press_percentile,
             py::arg("render_cell_mm") = api::TrackerOptions{}.render_cell_mm, py::arg("threads") = 0,
             py::arg("free_space_mm") = api::TrackerOptions{}.free_space_mm,
             py::arg("render_refined_weight") = api::TrackerOptions{}.render_refined_weight,
             py::arg("render_slack_rounds") = api::TrackerOptions{}.render_slack_rounds,
             py::arg("field_slack") = api::TrackerOptions{}.field_slack,
             py::arg("render_refined_floor") = api::TrackerOptions{}.render_refined_floor, py::arg("profile") = false,
             py::keep_alive<1, 2>())
        .def(
            "add_touch",
            [](api::Tracker& t, const py::object& motion, const api::TouchResult* result, const api::Object* object,
               const py::object& shape) {
                std::optional<api::Motion> mo;
                if (!motion.is_none()) mo = to_motion(motion, "motion");
                std::optional<api::GelShape> g;
                if (!shape.is_none()) g = to_shape(shape);
                py::gil_scoped_release release;
                t.add_touch(mo, result, object, g ? &*g : nullptr);
            },
            py::arg("motion") = py::none(), py::arg("result") = nullptr, py::arg("object") = nullptr, py::arg("shape") = py::none())
        .def(
            "check_motion",
            [](const api::Tracker& t, const py::object& motion, int touch) { t.check_motion(to_motion(motion, "motion"), touch); },
            py::arg("motion"), py::arg("touch"),
            "Raises what add_touch would for this motion arriving as touch `touch` (2 and later), and nothing else: "
            "not a rigid motion, or the sensor moved farther than max_hop.")
        .def_property_readonly("max_hop", &api::Tracker::max_hop,
                               "How far the sensor can move between two touches of this object (its bounding box's diagonal, "
                               "the presses, the odometry noise; the tracker's units): a motion farther is refused.")
        .def(
            "add_touch_term",
            [](api::Tracker& t, const py::object& motion, const py::object& term, const py::object& shape) {
                std::optional<api::Motion> mo;
                if (!motion.is_none()) mo = to_motion(motion, "motion");
                std::vector<float> v;
                if (!term.is_none()) {
                    const auto a = term.cast<py::array_t<float, py::array::c_style | py::array::forcecast>>();
                    v.assign(a.data(), a.data() + a.size());
                }
                std::optional<api::GelShape> g;
                if (!shape.is_none()) g = to_shape(shape);
                py::gil_scoped_release release;
                t.add_touch_term(mo, v, g ? &*g : nullptr);
            },
            py::arg("motion") = py::none(), py::arg("term") = py::none(), py::arg("shape") = py::none(),
            "add_touch with a precomputed log term (shape_term's, or None: geometry only); shape: the touch's gel "
            "shape for render-and-compare at the refined poses (render_refined_weight), or None.")
        .def(
            "shape_term",
            [](api::Tracker& t, const py::object& shape) {
                const api::GelShape g = to_shape(shape);
                std::vector<float> v;
                {
                    py::gil_scoped_release release;
                    v = t.shape_term(g);
                }
                return floats(v);
            },
            py::arg("shape"), "Render-and-compare's log term of one gel shape over the hypotheses (belief order).")
        .def("estimate", [](const api::Tracker& t) { return estimate_dict(without_gil([&] { return t.estimate(); })); })
        .def(
            "evaluate_window",
            [](api::Tracker& t, const py::list& motions, const py::object& terms, const py::object& shapes) {
                std::vector<api::Motion> ms;
                for (size_t i = 0; i < motions.size(); ++i) ms.push_back(to_motion(motions[i], "motions[" + std::to_string(i) + "]"));
                if (terms.is_none() && shapes.is_none()) return estimate_dict(without_gil([&] { return t.evaluate_window(ms); }));
                std::vector<std::vector<float>> ts;
                if (!terms.is_none())
                    for (const py::handle& h : terms.cast<py::list>()) {
                        if (h.is_none()) {
                            ts.emplace_back();
                            continue;
                        }
                        const auto a = h.cast<py::array_t<float, py::array::c_style | py::array::forcecast>>();
                        ts.emplace_back(a.data(), a.data() + a.size());
                    }
                std::vector<std::optional<api::GelShape>> gs;
                if (!shapes.is_none())
                    for (const py::handle& h : shapes.cast<py::list>()) gs.push_back(h.is_none() ? std::nullopt : std::optional(to_shape(py::reinterpret_borrow<py::object>(h))));
                std::vector<const api::GelShape*> gp;
                for (const auto& g : gs) gp.push_back(g ? &*g : nullptr);
                return estimate_dict(without_gil([&] { return t.evaluate_window_terms(ms, ts, gp); }));
            },
            py::arg("motions"), py::arg("terms") = py::none(), py::arg("shapes") = py::none(),
            "The windowed form: a list of the W - 1 motions between W touches; terms: one log term per touch "
            "(shape_term's, or None), computed once and reused across windows; shapes: one gel shape per touch "
            "(or None) for render-and-compare at the refined poses.")
        .def(
            "window_fit",
            [](const api::Tracker& t, const py::list& motions, const py::object& pose) {
                std::vector<api::Motion> ms;
                for (size_t i = 0; i < motions.size(); ++i) ms.push_back(to_motion(motions[i], "motions[" + std::to_string(i) + "]"));
                const api::Motion p = to_motion(pose, "pose");
                py::gil_scoped_release release;
                return t.window_fit(ms, p);
            },
            py::arg("motions"), py::arg("pose"),
            "The geometry fit (log) of a 4 x 4 pose of the window's last touch, refined from it: above "
            "estimate()['fit'] the search missed it, at or below a wrong pose fits as well.")
        .def(
            "with_options",
            [](const api::Tracker& t, const py::kwargs& kw) {
                api::TrackerOptions o = t.options();  // what is not named stays this tracker's
                for (const auto& [key, value] : kw) {
                    const std::string k = key.cast<std::string>();
                    try {
                        const NamedOption* n = std::find_if(std::begin(kOptions), std::end(kOptions),
                                                            [&](const NamedOption& x) { return k == x.name; });
                        if (n == std::end(kOptions))
                            throw api::Error("with_options: no option '" + k + "' (Tracker.options names them all but candidates)");
                        // n_spin, hypotheses and object_units are refused by the engine where they differ.
                        std::visit([&](auto m) { o.*m = value.cast<std::remove_reference_t<decltype(o.*m)>>(); }, n->member);
                    } catch (const py::cast_error&) {
                        throw api::Error("with_options: " + k + " has the wrong type");
                    }
                }
                py::gil_scoped_release free;
                return t.with_options(o);
            },
            "A new tracker (no touches) on this one's object with the named options changed, its surface "
            "not built again; options that shape the surface (n_spin, hypotheses, object_units) must stay. "
            "It keeps this tracker (and so its context) alive.",
            py::keep_alive<0, 1>())
        .def_property_readonly("options", [](const api::Tracker& t) { return options_dict(t.options()); },
                               "Every option of this tracker by name (candidates as a C x 3 array or None).")
        .def("reset", &api::Tracker::reset, py::call_guard<py::gil_scoped_release>(),
             "Forgets every touch (a new grasp); the object's tables stay.")
        .def_property_readonly("touches", py::cpp_function(&api::Tracker::touches, py::call_guard<py::gil_scoped_release>()))
        .def_property_readonly("belief", [](const api::Tracker& t) { return floats(without_gil([&] { return t.belief(); })); })
        .def_property_readonly("sample_points", [](const api::Tracker& t) {
            std::vector<float> p = t.sample_points();
            py::array_t<float> a({py::ssize_t(p.size() / 3), py::ssize_t(3)});
            std::copy(p.begin(), p.end(), a.mutable_data());
            return a;
        })
        .def_property_readonly("n_spin", &api::Tracker::n_spin)
        .def_property_readonly("spacing_mm", &api::Tracker::spacing_mm)
        .def_property_readonly("device_bytes", py::cpp_function(&api::Tracker::device_bytes, py::call_guard<py::gil_scoped_release>()))
        .def_property_readonly("host_bytes", py::cpp_function(&api::Tracker::host_bytes, py::call_guard<py::gil_scoped_release>()))
        .def_property_readonly("step_nodes", py::cpp_function(&api::Tracker::step_nodes, py::call_guard<py::gil_scoped_release>()),
                               "The last step's GPU time per node: (name, ms) pairs in run order; profile=True only.");
}

}  // namespace vtloc::python
