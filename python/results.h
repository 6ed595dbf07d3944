#pragma once
// API results as Python objects holding numpy arrays.
#include <pybind11/pybind11.h>

#include <vtloc/vtloc.h>

namespace vtloc::python {

namespace py = pybind11;

// Registers TouchResult (read-only attributes, numpy arrays).
void bind_results(py::module_& m);

py::dict timings_dict(const api::Timings& t);
py::dict model_info_dict(const api::ModelInfo& info);
py::dict device_dict(const api::DeviceInfo& d);

}  // namespace vtloc::python
