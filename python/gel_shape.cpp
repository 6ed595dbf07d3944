// vtloc.GelShapeReader: the gel's shape from a frame (SPEC 9), numpy in and out.
#include <pybind11/pybind11.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "python/arrays.h"

namespace vtloc::python {

namespace {

py::array_t<float> grid(const std::vector<float>& v, int H, int W) {
    py::array_t<float> a({H, W});
    std::copy(v.begin(), v.end(), a.mutable_data());
    return a;
}

}  // namespace

void bind_gel_shape(py::module_& m) {
    py::class_<api::GelShapeReader>(m, "GelShapeReader",
                                    "The gel's shape from a GelSight frame (SPEC section 9) on the GPU: read(frame, empty=None)\n"
                                    "-> dict of depth_mm, grad_row, grad_col (H x W float32), mask (H x W uint8), mm_per_px.\n"
                                    "Frames: H x W x 3 uint8 RGB or a path; larger frames of the calibration's aspect are resampled.")
        .def(py::init([](api::Context& ctx, const std::string& calibration, double mask_threshold, int iterations, bool match_lighting,
                         int levels, int coarse_iterations) {
                 api::GelShapeOptions o;
                 o.calibration = calibration, o.mask_threshold = mask_threshold, o.iterations = iterations;
                 o.levels = levels, o.coarse_iterations = coarse_iterations;
                 o.match_lighting = match_lighting;
                 return api::GelShapeReader(ctx, o);
             }),
             py::arg("context"), py::arg("calibration") = "", py::arg("mask_threshold") = 0.7, py::arg("iterations") = api::GelShapeOptions{}.iterations,
             py::arg("match_lighting") = true, py::arg("levels") = api::GelShapeOptions{}.levels,
             py::arg("coarse_iterations") = api::GelShapeOptions{}.coarse_iterations, py::keep_alive<1, 2>())
        .def(
            "read",
            [](api::GelShapeReader& r, const py::object& frame, const py::object& empty) {
                const api::TactileImage f = to_image(frame, "frame");
                std::optional<api::TactileImage> e;
                if (!empty.is_none()) e = to_image(empty, "empty");
                // A frame given as a path names its file in the reader's errors.
                const std::string fname = py::isinstance<py::str>(frame) ? frame.cast<std::string>() : "frame";
                const std::string ename = py::isinstance<py::str>(empty) ? empty.cast<std::string>() : "empty frame";
                api::GelShape s;
                {
                    py::gil_scoped_release release;
                    s = r.read(f, e ? &*e : nullptr, fname, ename);
                }
                py::dict d;
                d["depth_mm"] = grid(s.depth_mm, s.height, s.width);
                d["grad_row"] = grid(s.grad_row, s.height, s.width);
                d["grad_col"] = grid(s.grad_col, s.height, s.width);
                py::array_t<uint8_t> mask({s.height, s.width});
                std::copy(s.mask.begin(), s.mask.end(), mask.mutable_data());
                d["mask"] = mask;
                d["mm_per_px"] = s.mm_per_px;
                return d;
            },
            py::arg("frame"), py::arg("empty") = py::none())
        .def_property_readonly("height", &api::GelShapeReader::height)
        .def_property_readonly("width", &api::GelShapeReader::width);
}

}  // namespace vtloc::python
