// The `vtloc` Python module: the public C++ API (<vtloc/vtloc.h>) with numpy
// arrays in and out. Every engine call runs with the GIL released; every
// failure is a vtloc.Error carrying the engine's one-line message.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "results.h"

namespace py = pybind11;
using namespace vtloc;

namespace vtloc::python {
void bind_model(py::module_& m);
void bind_tracker(py::module_& m);
void bind_gel_shape(py::module_& m);
void bind_check(py::module_& m);
}

namespace {

api::Validation validation_of(const py::object& v) {
    if (v.is_none()) return api::Validation::Environment;
    return v.cast<bool>() ? api::Validation::On : api::Validation::Off;
}

}  // namespace

PYBIND11_MODULE(vtloc, m) {
    m.doc() = "VTLoc: visual-tactile contact localisation on the GPU (Vulkan compute).\n\n"
              "    ctx = vtloc.Context()\n"
              "    model = vtloc.Model(ctx, 'models/vtloc-lite-everyday.safetensors')\n"
              "    obj = model.encode_object('object.ply')\n"
              "    r = model.localize(obj, 'touch.png')   # or an H x W x 3 uint8 array\n"
              "    r.contact, r.topk_point, r.heatmap       # numpy arrays\n";
    static py::exception<api::Error> error(m, "Error");
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const api::Error& e) {
            error(e.what());
        }
    });

    m.def("version", &api::version, "The engine's version.");
    m.def("list_devices", [] {
        std::vector<api::DeviceInfo> devs;
        {
            py::gil_scoped_release release;
            devs = api::list_devices();
        }
        py::list out;
        for (const auto& d : devs) out.append(python::device_dict(d));
        return out;
    }, "Every Vulkan device with a compute queue, as dicts.");
    m.def("device_profile", [](int index) {
        py::gil_scoped_release release;
        return api::device_profile(index);
    }, py::arg("index"), "Device `index`'s limits as a device profile (JSON text) for vtloc-bench --plan-for.");
    m.def("inspect_model", [](const std::string& path) {
        api::ModelInfo info;
        {
            py::gil_scoped_release release;
            info = api::inspect_model(path);
        }
        return python::model_info_dict(info);
    }, py::arg("path"), "Reads and checks a weight file without a GPU; its config and tensors as a dict.");
    m.def("load_tactile_image", [](const std::string& path) {
        api::TactileImage im;
        {
            py::gil_scoped_release release;
            im = api::load_tactile_image(path);
        }
        return python::image_array(im);
    }, py::arg("path"), "A tactile image file as an H x W x 3 uint8 RGB array.");

    py::class_<api::Context>(m, "Context", "A Vulkan device and queue. Models made on it may be shared between threads (a Model's calls run one at a time); for parallel work use one context per thread.")
        .def(py::init([](const std::string& device, const py::object& validation) {
                 api::ContextOptions o;
                 o.device = device;
                 o.validation = validation_of(validation);
                 py::gil_scoped_release release;
                 return new api::Context(o);
             }),
             py::arg("device") = "", py::arg("validation") = py::none(),
             "device: '' (VTLOC_DEVICE, else the best device), an index or a name substring.\n"
             "validation: None (VTLOC_VALIDATION decides), True or False.")
        .def_property_readonly("device", [](const api::Context& c) { return python::device_dict(c.device()); })
        .def_property_readonly("validation_enabled", &api::Context::validation_enabled)
        .def("take_validation_messages", &api::Context::take_validation_messages,
             "Validation-layer warnings and errors since the last call.");

    python::bind_results(m);
    python::bind_model(m);
    python::bind_tracker(m);
    python::bind_gel_shape(m);
    python::bind_check(m);
}
