#pragma once
// numpy <-> API conversions for the Python module. Arrays are checked, never
// silently converted: a wrong dtype, shape or layout is a vtloc.Error naming
// the argument, what it got and what it needs.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <array>
#include <string>
#include <vector>

#include <vtloc/vtloc.h>

namespace vtloc::python {

namespace py = pybind11;

// f() with the GIL released: engine work, or a wait for an object's lock, must not stop the
// caller's other Python threads. Its result is converted to Python after the GIL is back.
template <class F>
auto without_gil(F&& f) -> decltype(f()) {
    py::gil_scoped_release release;
    return f();
}

// "float32 array of shape (3, 4)" for error messages.
std::string describe(const py::array& a);

// A tactile frame: an H x W x 3 uint8 C-contiguous array (RGB), or a path.
api::TactileImage to_image(const py::handle& obj, const std::string& what);
// One frame or a list/tuple of frames.
std::vector<api::TactileImage> to_images(const py::handle& obj, const std::string& what);

// N x 6 (x y z nx ny nz) or N x 3 (x y z: normals estimated at encoding)
// float32/float64 points: checked finite.
api::PointCloud to_cloud(const py::handle& obj, const std::string& what);
// M x 3 float32/float64 -> 3 floats each; None -> empty.
std::vector<float> to_points3(const py::handle& obj, const std::string& what);
// T x 3 float -> rows.
std::vector<std::array<double, 3>> to_rows3(const py::handle& obj, const std::string& what);
// A length-P float array (a heat value per cloud point).
std::vector<float> to_floats(const py::handle& obj, const std::string& what);

py::array_t<float> floats(const std::vector<float>& v);
py::array_t<int32_t> ints(const std::vector<int32_t>& v);
py::array_t<double> vec3(const std::array<double, 3>& v);
py::array_t<double> rows3(const std::vector<std::array<double, 3>>& v);
py::array_t<uint8_t> image_array(const api::TactileImage& im);
// A SPEC section 8 tensor with its shape (float32, int32 or uint8).
py::array tensor_array(const api::Tensor& t);

}  // namespace vtloc::python
