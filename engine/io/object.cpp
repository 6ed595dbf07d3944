#include "engine/io/object.h"

#include <algorithm>
#include <cmath>

#include "engine/io/file_bytes.h"
#include "engine/io/mesh_formats.h"
#include "engine/io/ply.h"
#include "engine/io/point_text.h"

namespace vtloc::io {

void check_cloud(HostTensor& cloud, const std::string& source) {
    const int64_t w = cloud.shape.size() == 2 ? cloud.shape[1] : 0;
    if (w != 3 && w != 6)
        fail(source, "point cloud must be N x 3 (xyz) or N x 6 (xyz, normal), got " + shape_str(cloud.shape));
    if (cloud.shape[0] == 0) fail(source, "the point cloud is empty");
    for (int64_t i = 0; i < cloud.shape[0]; ++i) {
        float* p = &cloud.data[size_t(i * w)];
        for (int k = 0; k < w; ++k)
            if (!std::isfinite(p[k]))
                fail(source, "point " + std::to_string(i) + " has a non-finite " + (k < 3 ? "coordinate" : "normal"));
        if (w == 3) continue;
        double len = std::sqrt(double(p[3]) * p[3] + double(p[4]) * p[4] + double(p[5]) * p[5]);
        if (len < 1e-12) fail(source, "point " + std::to_string(i) + " has a zero normal");
        if (std::abs(len - 1.0) > 1e-4)
            for (int k = 3; k < 6; ++k) p[k] = float(p[k] / len);
    }
}

namespace {

bool has_normals(const PlyVertices& v) { return v.column("nx") >= 0 && v.column("ny") >= 0 && v.column("nz") >= 0; }

}  // namespace

HostTensor load_ply_cloud(const std::string& path) {
    PlyVertices v = read_ply_vertices(path);
    if (!has_normals(v)) fail(path, "PLY point cloud has no normals (properties nx, ny, nz); the model needs them");
    HostTensor cloud = ply_columns(v, {"x", "y", "z", "nx", "ny", "nz"}, path);
    check_cloud(cloud, path);
    return cloud;
}

HostTensor load_object(const std::string& path, int64_t n_points, uint64_t seed) {
    std::string ext = extension_of(path);
    HostTensor c;
    if (ext == "glb" || ext == "gltf") {
        c = sample_surface(load_gltf_mesh(path), n_points, seed, path);
    } else if (ext == "obj" || ext == "off" || ext == "stl") {
        c = sample_surface(load_mesh(path), n_points, seed, path);
    } else if (ext == "ply") {
        const PlyVertices v = read_ply_vertices(path);
        const bool faces = std::find(v.elements.begin(), v.elements.end(), "face") != v.elements.end();
        if (has_normals(v)) c = ply_columns(v, {"x", "y", "z", "nx", "ny", "nz"}, path);
        else if (faces) c = sample_surface(load_mesh(path), n_points, seed, path);
        else c = ply_columns(v, {"x", "y", "z"}, path);
    } else if (ext == "xyz" || ext == "csv" || ext == "txt") {
        c = load_point_text(path, "points", true);
    } else if (ext == "pcd") {
        c = load_pcd(path);
    } else {
        fail(path, "unknown object file type '." + ext +
                       "' (meshes: .glb .gltf .obj .off .stl .ply with faces; clouds: .ply .pcd .xyz .csv .txt)");
    }
    check_cloud(c, path);
    return c;
}

void require_points(const HostTensor& cloud, int64_t needed, const std::string& source) {
    int64_t have = cloud.shape.empty() ? 0 : cloud.shape[0];
    if (have < needed)
        fail(source, "the object has " + std::to_string(have) + " points, the model needs at least " +
                         std::to_string(needed));
}

}  // namespace vtloc::io
