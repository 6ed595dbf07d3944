#include "results.h"

#include <pybind11/stl.h>

#include "arrays.h"

namespace vtloc::python {

py::dict timings_dict(const api::Timings& t) {
    py::dict d;
    d["wall_ms"] = t.wall_ms;
    d["gpu_ms"] = t.gpu_ms;
    py::list nodes;
    for (const auto& [name, ms] : t.nodes) nodes.append(py::make_tuple(name, ms));
    d["nodes"] = nodes;
    return d;
}

py::dict device_dict(const api::DeviceInfo& x) {
    py::dict d;
    d["index"] = x.index;
    d["name"] = x.name;
    d["type"] = x.type;
    d["api_version"] = py::make_tuple(x.api_major, x.api_minor);
    d["subgroup_size"] = x.subgroup_size;
    d["shared_memory_bytes"] = x.shared_memory_bytes;
    d["max_workgroup_invocations"] = x.max_workgroup_invocations;
    d["max_workgroup_size"] = py::make_tuple(x.max_workgroup_size[0], x.max_workgroup_size[1], x.max_workgroup_size[2]);
    d["max_workgroup_count"] =
        py::make_tuple(x.max_workgroup_count[0], x.max_workgroup_count[1], x.max_workgroup_count[2]);
    d["max_storage_buffer_bytes"] = x.max_storage_buffer_bytes;
    d["timestamps"] = x.timestamps;
    d["device_local_bytes"] = x.device_local_bytes;
    d["host_vector_registers"] = x.host_vector_registers;
    d["compute_units"] = x.compute_units;
    return d;
}

py::dict model_info_dict(const api::ModelInfo& i) {
    py::dict d;
    d["path"] = i.path;
    d["name"] = i.name;
    d["config_json"] = i.config_json;
    d["head"] = i.head;
    d["feature_size"] = i.feature_size;
    d["default_k"] = i.default_k;
    d["default_iters"] = i.default_iters;
    d["use_normals"] = i.use_normals;
    d["has_gma"] = i.has_gma;
    d["crop"] = i.crop;
    d["input_size"] = i.input_size;
    d["sample_points"] = i.sample_points;
    d["min_points"] = i.min_points;
    if (i.sensor) {
        py::dict s;
        s["mm_per_px"] = i.sensor->mm_per_px;
        s["height"] = i.sensor->height;
        s["width"] = i.sensor->width;
        d["sensor"] = s;
    } else {
        d["sensor"] = py::none();
    }
    d["parameter_count"] = i.parameter_count;
    d["size_mib"] = i.size_mib;
    d["file_bytes"] = i.file_bytes;
    py::list tensors;
    for (const auto& t : i.tensors) tensors.append(py::make_tuple(t.name, t.dtype, py::tuple(py::cast(t.shape))));
    d["tensors"] = tensors;
    return d;
}

void bind_results(py::module_& m) {
    py::class_<api::TouchResult>(m, "TouchResult", "One touch's result; coordinates in the object's units.")
        .def_property_readonly("contact", [](const api::TouchResult& r) { return vec3(r.contact); },
                               "c^p, shape (3,), float64")
        .def_property_readonly("contact_normalised", [](const api::TouchResult& r) { return vec3(r.contact_normalised); })
        .def_property_readonly("iterates", [](const api::TouchResult& r) { return rows3(r.iterates); },
                               "ILU iterates c_1..c_N, shape (N, 3)")
        .def_property_readonly("iterates_normalised", [](const api::TouchResult& r) { return rows3(r.iterates_normalised); })
        .def_property_readonly("topk_index", [](const api::TouchResult& r) { return ints(r.topk_index); },
                               "indices into Object.candidates, best first, int32")
        .def_property_readonly("topk_score", [](const api::TouchResult& r) { return floats(r.topk_score); },
                               "||c^p - c_i||^2 in the normalised frame, float32")
        .def_property_readonly("topk_point", [](const api::TouchResult& r) { return rows3(r.topk_point); })
        .def_property_readonly("heatmap", [](const api::TouchResult& r) { return floats(r.heatmap); },
                               "one value in [0, 1] per Object.cloud point, float32")
        .def_property_readonly("alignment", [](const api::TouchResult& r) -> py::object {
            return r.alignment ? py::cast(*r.alignment) : py::none();
        }, "chamfer(P^d, P) when GMA ran, else None")
        .def_property_readonly("timings", [](const api::TouchResult& r) { return timings_dict(r.timings); })
        .def_property_readonly("tensors", [](const api::TouchResult& r) {
            py::dict d;
            for (const auto& t : r.tensors) d[py::str(t.name)] = tensor_array(t);
            return d;
        }, "every intermediate tensor by its SPEC section 8 name (keep_tensors=True)")
        .def("__repr__", [](const api::TouchResult& r) {
            return "<vtloc.TouchResult contact=(" + std::to_string(r.contact[0]) + ", " + std::to_string(r.contact[1]) +
                   ", " + std::to_string(r.contact[2]) + ")>";
        });
}

}  // namespace vtloc::python
