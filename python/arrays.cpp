#include "arrays.h"

#include <cmath>
#include <cstring>

namespace vtloc::python {

namespace {

[[noreturn]] void fail(const std::string& msg) { throw api::Error(msg); }

py::array need_array(const py::handle& obj, const std::string& what) {
    if (!py::isinstance<py::array>(obj))
        fail(what + ": expected a numpy array, got " + std::string(py::str(py::type::of(obj).attr("__name__"))));
    py::array a = py::reinterpret_borrow<py::array>(obj);
    if (!(a.flags() & py::array::c_style))
        fail(what + ": the " + describe(a) + " is not C-contiguous; pass numpy.ascontiguousarray(...)");
    return a;
}

bool is_float(const py::array& a) {
    return a.dtype().is(py::dtype::of<float>()) || a.dtype().is(py::dtype::of<double>());
}

// Rows of `cols` floats, float32 or float64, every value finite.
std::vector<double> float_rows(const py::handle& obj, const std::string& what, long cols, const char* layout) {
    py::array a = need_array(obj, what);
    if (!is_float(a) || a.ndim() != 2 || a.shape(1) != cols)
        fail(what + ": expected a float32 or float64 array of shape (N, " + std::to_string(cols) + ") (" + layout +
             (cols == 6 ? "; or (N, 3) without normals" : "") + "), got a " + describe(a));
    const size_t n = size_t(a.size());
    std::vector<double> out(n);
    if (a.dtype().is(py::dtype::of<float>())) {
        const float* p = static_cast<const float*>(a.data());
        for (size_t i = 0; i < n; ++i) out[i] = p[i];
    } else {
        std::memcpy(out.data(), a.data(), n * sizeof(double));
    }
    for (size_t i = 0; i < n; ++i)
        if (!std::isfinite(out[i]))
            fail(what + ": row " + std::to_string(i / cols) + " holds NaN or inf");
    return out;
}

}  // namespace

std::string describe(const py::array& a) {
    std::string shape = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(a.shape(i));
    if (a.ndim() == 1) shape += ",";
    return std::string(py::str(a.dtype())) + " array of shape " + shape + ")";
}

api::TactileImage to_image(const py::handle& obj, const std::string& what) {
    if (py::isinstance<py::str>(obj)) return api::load_tactile_image(obj.cast<std::string>());
    py::array a = need_array(obj, what);
    if (!a.dtype().is(py::dtype::of<uint8_t>()) || a.ndim() != 3 || a.shape(2) != 3)
        fail(what + ": expected an H x W x 3 uint8 RGB array or a path, got a " + describe(a));
    api::TactileImage im;
    im.height = int(a.shape(0));
    im.width = int(a.shape(1));
    im.rgb.assign(static_cast<const uint8_t*>(a.data()), static_cast<const uint8_t*>(a.data()) + a.size());
    return im;
}

std::vector<api::TactileImage> to_images(const py::handle& obj, const std::string& what) {
    std::vector<api::TactileImage> out;
    if (py::isinstance<py::list>(obj) || py::isinstance<py::tuple>(obj)) {
        size_t i = 0;
        for (const py::handle& item : obj) out.push_back(to_image(item, what + "[" + std::to_string(i++) + "]"));
        if (out.empty()) fail(what + ": the list of frames is empty");
    } else {
        out.push_back(to_image(obj, what));
    }
    return out;
}

api::PointCloud to_cloud(const py::handle& obj, const std::string& what) {
    long cols = 6;
    if (py::isinstance<py::array>(obj)) {
        py::array a = py::reinterpret_borrow<py::array>(obj);
        if (a.ndim() == 2 && a.shape(1) == 3) cols = 3;
    }
    const std::vector<double> v = float_rows(obj, what, cols, cols == 6 ? "x y z nx ny nz" : "x y z");
    api::PointCloud c;
    const size_t n = v.size() / size_t(cols);
    if (n == 0) fail(what + ": the cloud is empty");
    c.xyz.resize(n * 3);
    if (cols == 6) c.normals.resize(n * 3);
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < 3; ++k) {
            c.xyz[i * 3 + k] = float(v[i * size_t(cols) + k]);
            if (cols == 6) c.normals[i * 3 + k] = float(v[i * 6 + 3 + k]);
        }
    return c;
}

std::vector<float> to_points3(const py::handle& obj, const std::string& what) {
    if (obj.is_none()) return {};
    const std::vector<double> v = float_rows(obj, what, 3, "x y z");
    if (v.empty()) fail(what + ": no points (pass None for the cloud's own points)");
    return std::vector<float>(v.begin(), v.end());
}

std::vector<std::array<double, 3>> to_rows3(const py::handle& obj, const std::string& what) {
    const std::vector<double> v = float_rows(obj, what, 3, "dx dy dz");
    std::vector<std::array<double, 3>> out(v.size() / 3);
    for (size_t i = 0; i < out.size(); ++i) out[i] = {v[i * 3], v[i * 3 + 1], v[i * 3 + 2]};
    return out;
}

std::vector<float> to_floats(const py::handle& obj, const std::string& what) {
    py::array a = need_array(obj, what);
    if (!is_float(a) || a.ndim() != 1) fail(what + ": expected a 1-D float32 or float64 array, got a " + describe(a));
    std::vector<float> out(size_t(a.size()));
    for (size_t i = 0; i < out.size(); ++i) {
        const double x = a.dtype().is(py::dtype::of<float>()) ? static_cast<const float*>(a.data())[i]
                                                                : static_cast<const double*>(a.data())[i];
        if (!std::isfinite(x)) fail(what + ": element " + std::to_string(i) + " is NaN or inf");
        out[i] = float(x);
    }
    return out;
}

py::array_t<float> floats(const std::vector<float>& v) {
    py::array_t<float> a(py::ssize_t(v.size()));
    if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(float));
    return a;
}

py::array_t<int32_t> ints(const std::vector<int32_t>& v) {
    py::array_t<int32_t> a(py::ssize_t(v.size()));
    if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(int32_t));
    return a;
}

py::array_t<double> vec3(const std::array<double, 3>& v) {
    py::array_t<double> a(3);
    std::memcpy(a.mutable_data(), v.data(), 3 * sizeof(double));
    return a;
}

py::array_t<double> rows3(const std::vector<std::array<double, 3>>& v) {
    py::array_t<double> a({py::ssize_t(v.size()), py::ssize_t(3)});
    if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), v.size() * 3 * sizeof(double));
    return a;
}

py::array_t<uint8_t> image_array(const api::TactileImage& im) {
    py::array_t<uint8_t> a({py::ssize_t(im.height), py::ssize_t(im.width), py::ssize_t(3)});
    if (!im.rgb.empty()) std::memcpy(a.mutable_data(), im.rgb.data(), im.rgb.size());
    return a;
}

py::array tensor_array(const api::Tensor& t) {
    std::vector<py::ssize_t> shape(t.shape.begin(), t.shape.end());
    if (!t.i32.empty()) {
        py::array_t<int32_t> a(shape);
        std::memcpy(a.mutable_data(), t.i32.data(), t.i32.size() * sizeof(int32_t));
        return a;
    }
    if (!t.u8.empty()) {
        py::array_t<uint8_t> a(shape);
        std::memcpy(a.mutable_data(), t.u8.data(), t.u8.size());
        return a;
    }
    py::array_t<float> a(shape);
    if (!t.f32.empty()) std::memcpy(a.mutable_data(), t.f32.data(), t.f32.size() * sizeof(float));
    return a;
}

}  // namespace vtloc::python
