#include "engine/io/object.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "engine/io/file_bytes.h"
#include "engine/io/mesh_formats.h"
#include "engine/io/ply.h"
#include "engine/io/point_text.h"

namespace vtloc::io {

void check_cloud(HostTensor& cloud, const std::string& source) {
    if (cloud.shape.size() != 2 || cloud.shape[1] != 6)
        fail(source, "point cloud must be N x 6 (xyz, normal), got " + shape_str(cloud.shape));
    for (int64_t i = 0; i < cloud.shape[0]; ++i) {
        float* p = &cloud.data[size_t(i) * 6];
        for (int k = 0; k < 6; ++k)
            if (!std::isfinite(p[k]))
                fail(source, "point " + std::to_string(i) + " has a non-finite " + (k < 3 ? "coordinate" : "normal"));
        double len = std::sqrt(double(p[3]) * p[3] + double(p[4]) * p[4] + double(p[5]) * p[5]);
        if (len < 1e-12) fail(source, "point " + std::to_string(i) + " has a zero normal");
        if (std::abs(len - 1.0) > 1e-4)
            for (int k = 3; k < 6; ++k) p[k] = float(p[k] / len);
    }
}

HostTensor load_ply_cloud(const std::string& path) {
    PlyVertices v = read_ply_vertices(path);
    if (v.column("nx") < 0 || v.column("ny") < 0 || v.column("nz") < 0)
        fail(path, "PLY point cloud has no normals (properties nx, ny, nz); the model needs them");
    HostTensor cloud = ply_columns(v, {"x", "y", "z", "nx", "ny", "nz"}, path);
    check_cloud(cloud, path);
    return cloud;
}

namespace {

// Whether a PLY header declares a face element (then the file is a mesh).
bool ply_has_faces(const std::string& path) {
    const std::vector<uint8_t> bytes = read_file_bytes(path);
    const std::string head(bytes.begin(), bytes.begin() + std::ptrdiff_t(std::min<size_t>(bytes.size(), 1 << 16)));
    const size_t end = head.find("end_header");
    return head.substr(0, end).find("\nelement face ") != std::string::npos;
}

HostTensor finite_xyz(HostTensor c, const std::string& path) {
    for (int64_t i = 0; i < c.shape[0]; ++i)
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(c.data[size_t(i * c.shape[1] + k)]))
                fail(path, "point " + std::to_string(i) + " has a non-finite coordinate");
    if (c.shape[0] == 0) fail(path, "the point cloud is empty");
    return c;
}

}  // namespace

HostTensor load_object(const std::string& path, int64_t n_points, uint64_t seed) {
    std::string ext = extension_of(path);
    if (ext == "glb" || ext == "gltf") return sample_surface(load_gltf_mesh(path), n_points, seed, path);
    if (ext == "obj" || ext == "off" || ext == "stl") return sample_surface(load_mesh(path), n_points, seed, path);
    if (ext == "ply") {
        PlyVertices v = read_ply_vertices(path);
        if (v.column("nx") >= 0 && v.column("ny") >= 0 && v.column("nz") >= 0) return load_ply_cloud(path);
        if (ply_has_faces(path)) return sample_surface(load_mesh(path), n_points, seed, path);
        return finite_xyz(ply_columns(v, {"x", "y", "z"}, path), path);
    }
    if (ext == "xyz" || ext == "csv" || ext == "txt") {
        HostTensor c = finite_xyz(load_point_text(path, "points", true), path);
        if (c.shape[1] == 6) check_cloud(c, path);
        return c;
    }
    if (ext == "pcd") {
        HostTensor c = load_pcd(path);
        if (c.shape[1] == 6) check_cloud(c, path);
        return c;
    }
    fail(path, "unknown object file type '." + ext +
                   "' (meshes: .glb .gltf .obj .off .stl .ply with faces; clouds: .ply .pcd .xyz .csv .txt)");
}

void require_points(const HostTensor& cloud, int64_t needed, const std::string& source) {
    int64_t have = cloud.shape.empty() ? 0 : cloud.shape[0];
    if (have < needed)
        fail(source, "the object has " + std::to_string(have) + " points, the model needs at least " +
                         std::to_string(needed));
}

}  // namespace vtloc::io
