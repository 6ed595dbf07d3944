// vtloc.GelShapeReader: the gel's shape from a frame (SPEC 9), numpy in and out.
#include <pybind11/pybind11.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <optional>
#include <string>

#include "python/arrays.h"

namespace vtloc::python {

namespace {

py::array_t<float> grid(const std::vector<float>& v, int H, int W) {
    py::array_t<float> a({H, W});
    std::copy(v.begin(), v.end(), a.mutable_data());
    return a;
}

// A frame and an optional empty frame as the reader takes them; one given as a path names its
// file in the reader's errors.
struct Frames {
    api::TactileImage frame;
    std::optional<api::TactileImage> empty;
    std::string frame_name, empty_name;
    Frames(const py::object& f, const py::object& e)
        : frame(to_image(f, "frame")),
          frame_name(py::isinstance<py::str>(f) ? f.cast<std::string>() : "frame"),
          empty_name(py::isinstance<py::str>(e) ? e.cast<std::string>() : "empty frame") {
        if (!e.is_none()) empty = to_image(e, "empty");
    }
    const api::TactileImage* empty_ptr() const { return empty ? &*empty : nullptr; }
};

}  // namespace

void bind_gel_shape(py::module_& m) {
    py::class_<api::GelShapeReader>(m, "GelShapeReader",
                                    "The gel's shape from a GelSight frame (SPEC section 9) on the GPU: read(frame, empty=None)\n"
                                    "-> dict of depth_mm, grad_row, grad_col (H x W float32), mask (H x W uint8), mm_per_px.\n"
                                    "Frames: H x W x 3 uint8 RGB or a path; larger frames of the calibration's aspect are resampled.")
        .def(py::init([](api::Context& ctx, const std::string& calibration, double mask_threshold, int iterations, bool match_lighting,
                         int levels, int coarse_iterations, int threads) {
                 api::GelShapeOptions o;
                 o.calibration = calibration, o.mask_threshold = mask_threshold, o.iterations = iterations;
                 o.levels = levels, o.coarse_iterations = coarse_iterations;
                 o.match_lighting = match_lighting, o.threads = threads;
                 py::gil_scoped_release release;  // the tables' build, about half a second
                 return api::GelShapeReader(ctx, o);
             }),
             py::arg("context"), py::arg("calibration") = "", py::arg("mask_threshold") = 0.7, py::arg("iterations") = api::GelShapeOptions{}.iterations,
             py::arg("match_lighting") = true, py::arg("levels") = api::GelShapeOptions{}.levels,
             py::arg("coarse_iterations") = api::GelShapeOptions{}.coarse_iterations, py::arg("threads") = 0, py::keep_alive<1, 2>())
        .def(
            "read",
            [](api::GelShapeReader& r, const py::object& frame, const py::object& empty) {
                const Frames in(frame, empty);
                api::GelShape s;
                {
                    py::gil_scoped_release release;
                    s = r.read(in.frame, in.empty_ptr(), in.frame_name, in.empty_name);
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
        .def(
            "check_frame",
            [](const api::GelShapeReader& r, const py::object& frame, const py::object& empty) {
                const Frames in(frame, empty);
                r.check_frame(in.frame, in.empty_ptr(), in.frame_name, in.empty_name);
            },
            py::arg("frame"), py::arg("empty") = py::none(),
            "Raises what read() would for these frames (size, aspect, a black or saturated frame), without the GPU.")
        .def_property_readonly("height", &api::GelShapeReader::height)
        .def_property_readonly("width", &api::GelShapeReader::width);
}

}  // namespace vtloc::python
