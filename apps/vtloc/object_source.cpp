// --object FILE, or a depth camera's view (--depth --intrinsics [--mask]
// [--depth-unit]): the object of a touch command (localize, sequence).
#include "cli.h"

namespace vtloc::cli {

const char* kObjectOptionsHelp =
    "  --object FILE             a mesh (.glb .gltf .obj .off .stl, .ply with faces; sampled to\n"
    "                            the model's point count) or a point cloud (.ply .pcd .xyz .csv);\n"
    "                            a cloud without normals gets estimated ones (k = 16, PCA)\n"
    "  --depth D.png             instead of --object: a depth camera's 16-bit PNG (mm, 0 = none);\n"
    "                            its partial cloud, camera frame, normals towards the camera\n"
    "  --intrinsics fx,fy,cx,cy  the depth camera's pinhole intrinsics (pixels), with --depth\n"
    "  --mask M.png              only the pixels where this image is nonzero (the object)\n"
    "  --depth-unit MM           millimetres per depth value (default 1)\n";

std::vector<OptionSpec> object_option_specs() {
    return {{"--object"}, {"--depth"}, {"--intrinsics"}, {"--mask"}, {"--depth-unit"}};
}

std::string object_label(const Args& a) {
    if (auto d = a.get("--depth")) return *d + " (depth view)";
    return a.get("--object").value_or("");
}

api::Object encode_cli_object(api::Model& model, const Args& a, const std::string& candidates, api::Backend backend) {
    const auto object = a.get("--object"), depth = a.get("--depth");
    if (object.has_value() == depth.has_value()) throw UsageError("give either --object or --depth");
    const bool camera = a.get("--intrinsics") || a.get("--mask") || a.get("--depth-unit");
    if (object) {
        if (camera) throw UsageError("--intrinsics, --mask and --depth-unit go with --depth");
        return model.encode_object(*object, candidates, backend);
    }
    const auto k = a.get("--intrinsics");
    if (!k) throw UsageError("--depth needs --intrinsics fx,fy,cx,cy");
    const std::vector<double> v = parse_numbers(*k, 4, "--intrinsics");
    double unit = 1.0;
    if (auto u = a.get("--depth-unit")) {
        unit = parse_numbers(*u, 1, "--depth-unit")[0];
        if (!(unit > 0)) throw UsageError("--depth-unit must be > 0 (mm per depth value)");
    }
    if (!(v[0] > 0) || !(v[1] > 0)) throw UsageError("--intrinsics: fx and fy must be > 0");
    api::PointCloud cloud = api::load_depth_cloud(*depth, {v[0], v[1], v[2], v[3]}, a.get("--mask").value_or(""), unit);
    return model.encode_object(cloud, candidates.empty() ? std::vector<float>{} : api::load_candidates(candidates), backend);
}

}  // namespace vtloc::cli
