// Model, Object and the touch calls of the Python module.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>

#include "arrays.h"
#include "results.h"

namespace vtloc::python {

namespace {

api::Backend backend_of(const std::string& s) {
    if (s == "gpu") return api::Backend::Gpu;
    if (s == "cpu") return api::Backend::Cpu;
    throw api::Error("backend must be 'gpu' or 'cpu', got '" + s + "'");
}

std::array<double, 3> triple(const py::handle& obj, const std::string& what) {
    try {
        auto v = obj.cast<std::vector<double>>();
        if (v.size() == 3) return {v[0], v[1], v[2]};
    } catch (const py::cast_error&) {
    }
    throw api::Error(what + ": expected 3 numbers");
}

std::optional<std::array<double, 3>> optional_triple(const py::object& obj, const std::string& what) {
    if (obj.is_none()) return std::nullopt;
    return triple(obj, what);
}

api::LocalizeOptions localize_options(int iters, int top_k, bool gma, const py::object& symmetry,
                                      const std::string& backend, bool keep_tensors, bool profile,
                                      const py::object& mm_per_px) {
    api::LocalizeOptions o;
    o.iters = iters;
    o.top_k = top_k;
    o.gma = gma;
    if (!symmetry.is_none()) {
        if (!py::isinstance<api::Symmetry>(symmetry)) throw api::Error("symmetry: expected a vtloc.Symmetry or None");
        o.symmetry = symmetry.cast<api::Symmetry>();
    }
    o.backend = backend_of(backend);
    o.keep_tensors = keep_tensors;
    o.profile = profile;
    if (!mm_per_px.is_none()) {
        if (!py::isinstance<py::float_>(mm_per_px) && !py::isinstance<py::int_>(mm_per_px))
            throw api::Error("mm_per_px: expected a number or None");
        o.mm_per_px = mm_per_px.cast<double>();
    }
    return o;
}

py::array_t<float> cloud_array(const api::PointCloud& c) {
    py::array_t<float> a({py::ssize_t(c.size()), py::ssize_t(6)});
    float* p = a.mutable_data();
    for (size_t i = 0; i < c.size(); ++i) {
        std::memcpy(p + i * 6, &c.xyz[i * 3], 3 * sizeof(float));
        std::memcpy(p + i * 6 + 3, &c.normals[i * 3], 3 * sizeof(float));
    }
    return a;
}

api::Object encode(api::Model& m, const py::object& source, const py::object& candidates, const std::string& backend,
                   const py::object& viewpoint) {
    const api::Backend b = backend_of(backend);
    if (!viewpoint.is_none() && py::isinstance<py::str>(source))
        throw api::Error("viewpoint: only for clouds given as arrays (a file's cloud is oriented away from its centroid)");
    const bool cand_path = py::isinstance<py::str>(candidates);
    if (py::isinstance<py::str>(source) && (candidates.is_none() || cand_path)) {
        const auto path = source.cast<std::string>();
        const auto cpath = cand_path ? candidates.cast<std::string>() : std::string();
        py::gil_scoped_release release;
        return m.encode_object(path, cpath, b);
    }
    std::vector<float> cands;
    if (cand_path) {
        const auto cpath = candidates.cast<std::string>();
        py::gil_scoped_release release;
        cands = api::load_candidates(cpath);
    } else {
        cands = to_points3(candidates, "candidates");
    }
    api::PointCloud cloud;
    if (py::isinstance<py::str>(source)) {
        const auto path = source.cast<std::string>();
        const int64_t n = m.info().sample_points;
        py::gil_scoped_release release;
        cloud = api::load_point_cloud(path, n);
    } else {
        cloud = to_cloud(source, "points");
        cloud.viewpoint = optional_triple(viewpoint, "viewpoint");
    }
    py::gil_scoped_release release;
    return m.encode_object(cloud, cands, b);
}

api::Object encode_depth(api::Model& mo, const std::string& depth, const py::object& intrinsics,
                         const py::object& mask, double unit_mm, const py::object& candidates,
                         const std::string& backend) {
    std::vector<double> k;
    try {
        k = intrinsics.cast<std::vector<double>>();
    } catch (const py::cast_error&) {
    }
    if (k.size() != 4) throw api::Error("intrinsics: expected 4 numbers fx, fy, cx, cy");
    const std::string m = mask.is_none() ? std::string() : mask.cast<std::string>();
    std::vector<float> cands = py::isinstance<py::str>(candidates)
                                   ? api::load_candidates(candidates.cast<std::string>())
                                   : to_points3(candidates, "candidates");
    const api::Backend b = backend_of(backend);
    py::gil_scoped_release release;
    api::PointCloud cloud = api::load_depth_cloud(depth, {k[0], k[1], k[2], k[3]}, m, unit_mm);
    return mo.encode_object(cloud, cands, b);
}

void render_png(const std::string& path, const api::Object& obj, const py::object& heat, int width, int height,
                const py::object& contact, const py::object& ground_truth, const py::object& up,
                const std::string& caption, const py::object& tactile, int display_points) {
    auto h = to_floats(heat, "heat");
    api::RenderOptions o;
    o.width = width;
    o.height = height;
    o.contact = optional_triple(contact, "contact");
    o.ground_truth = optional_triple(ground_truth, "ground_truth");
    const auto u = triple(up, "up");
    o.up = {float(u[0]), float(u[1]), float(u[2])};
    o.caption = caption;
    o.display_points = display_points;
    std::optional<api::TactileImage> frame;
    if (!tactile.is_none()) frame = to_image(tactile, "tactile");
    o.tactile = frame ? &*frame : nullptr;
    py::gil_scoped_release release;
    api::render_heatmap_png(path, obj, h, o);
}

const char* kLocalizeDoc =
    "Localises one touch (image: H x W x 3 uint8 RGB array or a path) -> TouchResult,\n"
    "or a batch (a list of them) -> list of TouchResult; frames of one size run in one submit.\n"
    "iters: ILU iterations 0..64 (-1: the model's); top_k: 0 = the model's K; gma: compute the\n"
    "alignment score; symmetry: a vtloc.Symmetry prior; backend: 'gpu' or 'cpu' (the C++ reference);\n"
    "keep_tensors: every intermediate in result.tensors; profile: per-node GPU times;\n"
    "mm_per_px: the frames' pixel size, rescaled to the model's sensor before the crop.";

void bind_symmetry(py::module_& m) {
    py::class_<api::Symmetry>(m, "Symmetry", "An M-fold rotational symmetry prior (object units).")
        .def(py::init([](const py::object& point, const py::object& direction, int order) {
                 return api::Symmetry{triple(point, "axis_point"), triple(direction, "axis_dir"), order};
             }),
             py::arg("axis_point"), py::arg("axis_dir"), py::arg("order"))
        .def_property_readonly("axis_point", [](const api::Symmetry& s) { return vec3(s.axis_point); })
        .def_property_readonly("axis_dir", [](const api::Symmetry& s) { return vec3(s.axis_dir); })
        .def_readonly("order", &api::Symmetry::order);
}

void bind_object(py::module_& m) {
    py::class_<api::Object>(m, "Object", "An encoded object (immutable; Model.encode_object makes one).")
        .def_property_readonly("source", &api::Object::source)
        .def_property_readonly("cloud", [](const api::Object& o) { return cloud_array(o.cloud()); },
                               "N x 6 float32: x y z nx ny nz, object units")
        .def_property_readonly("candidates", [](const api::Object& o) {
            py::array_t<float> a({py::ssize_t(o.candidate_count()), py::ssize_t(3)});
            if (o.candidate_count()) std::memcpy(a.mutable_data(), o.candidates().data(), o.candidates().size() * 4);
            return a;
        }, "M x 3 float32 candidate contact points, object units")
        .def_property_readonly("candidate_count", &api::Object::candidate_count)
        .def_property_readonly("centre", [](const api::Object& o) { return vec3(o.centre()); })
        .def_property_readonly("scale", &api::Object::scale)
        .def_property_readonly("normals_estimated", &api::Object::normals_estimated,
                               "True when the input had no normals and cloud holds estimated ones")
        .def_property_readonly("source_points", &api::Object::source_points,
                               "points in the input (a cloud of >= 100,000 is reduced to the model's count)");
}

void bind_model_class(py::module_& m) {
    py::class_<api::Model>(m, "Model", "A weight file loaded on a Context (or CPU-only without one).")
        .def(py::init([](api::Context& ctx, const std::string& path) {
                 py::gil_scoped_release release;
                 return new api::Model(ctx, path);
             }),
             py::arg("context"), py::arg("path"), py::keep_alive<1, 2>())
        .def(py::init([](const std::string& path) {
                 py::gil_scoped_release release;
                 return new api::Model(path);
             }),
             py::arg("path"), "CPU-only model: backend='cpu' calls only, no Vulkan needed.")
        .def_property_readonly("info", [](const api::Model& mo) { return model_info_dict(mo.info()); })
        .def("encode_object", &encode, py::arg("source"), py::arg("candidates") = py::none(),
             py::arg("backend") = "gpu", py::arg("viewpoint") = py::none(),
             "Runs the point branch once. source: a mesh or cloud file (a mesh is sampled to\n"
             "info['sample_points']) or an N x 6 (x y z nx ny nz) or N x 3 float array; a cloud\n"
             "without normals gets estimated ones (object.normals_estimated); candidates: None\n"
             "(the cloud's own points), an M x 3 float array or a file; viewpoint: estimated\n"
             "normals of an array face this point (a camera), else away from the centroid.")
        .def("encode_depth", &encode_depth,
             py::arg("depth"), py::arg("intrinsics"), py::arg("mask") = py::none(), py::arg("unit_mm") = 1.0,
             py::arg("candidates") = py::none(), py::arg("backend") = "gpu",
             "A depth camera's view as the object: a 16-bit depth PNG (value * unit_mm = mm, 0 = none),\n"
             "intrinsics (fx, fy, cx, cy) in pixels, an optional mask image (nonzero = the object).\n"
             "The partial cloud is in the camera frame (mm); normals are estimated facing the camera.")
        .def("localize",
             [](api::Model& mo, const api::Object& obj, const py::object& image, int iters, int top_k, bool gma,
                const py::object& symmetry, const std::string& backend, bool keep_tensors, bool profile,
                const py::object& mm_per_px) -> py::object {
                 const auto opt = localize_options(iters, top_k, gma, symmetry, backend, keep_tensors, profile, mm_per_px);
                 const bool batch = py::isinstance<py::list>(image) || py::isinstance<py::tuple>(image);
                 auto images = to_images(image, "image");
                 std::vector<api::TouchResult> rs;
                 {
                     py::gil_scoped_release release;
                     rs = mo.localize(obj, images, opt);
                 }
                 return batch ? py::cast(std::move(rs)) : py::cast(std::move(rs.front()));
             },
             py::arg("object"), py::arg("image"), py::arg("iters") = -1, py::arg("top_k") = 0, py::arg("gma") = true,
             py::arg("symmetry") = py::none(), py::arg("backend") = "gpu", py::arg("keep_tensors") = false,
             py::arg("profile") = false, py::arg("mm_per_px") = py::none(), kLocalizeDoc);
}

void bind_outputs(py::module_& m) {
    m.def("write_heatmap_ply",
          [](const std::string& path, const api::Object& obj, const py::object& heat) {
              auto h = to_floats(heat, "heat");
              py::gil_scoped_release release;
              api::write_heatmap_ply(path, obj, h);
          },
          py::arg("path"), py::arg("object"), py::arg("heat"),
          "PLY of the object's points with contact_prob and an RGB colour per point.");
    m.def("render_heatmap_png", &render_png,
          py::arg("path"), py::arg("object"), py::arg("heat"), py::arg("width") = 1280, py::arg("height") = 720,
          py::arg("contact") = py::none(), py::arg("ground_truth") = py::none(), py::arg("up") = py::make_tuple(0, 1, 0),
          py::arg("caption") = "", py::arg("tactile") = py::none(), py::arg("display_points") = 30000,
          "PNG picture of a heat-map over the object from two sides.");
}

}  // namespace

void bind_model(py::module_& m) {
    bind_symmetry(m);
    bind_object(m);
    bind_model_class(m);
    bind_outputs(m);
}

}  // namespace vtloc::python
