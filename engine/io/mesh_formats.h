#pragma once
// Triangle meshes from the common file formats, by extension: .off (also
// COFF/NOFF headers), .obj, .ply (with a face element), .stl (ASCII or
// binary), .gltf/.glb (load_gltf_mesh). Polygons are fan-triangulated,
// degenerate triangles (repeated vertex or zero area) are dropped, open
// meshes and non-manifold edges are accepted as they are.
#include <string>

#include "engine/io/mesh.h"

namespace vtloc::io {

// Largest coordinate magnitude accepted; beyond it a file is surely broken.
inline constexpr double kMaxMeshCoordinate = 1e7;

// Throws vtloc::Error, one line naming the file, for: a missing or unreadable
// file, an unknown extension, a malformed header or body (naming the line or
// element), indices out of range, NaN/inf coordinates, absurd sizes, and a
// mesh left with no triangle of non-zero area.
TriangleMesh load_mesh(const std::string& path);

// Binary little-endian PLY with vertex (x y z float) and face (uchar count,
// int indices): what the dataset builder stores, readable by load_mesh.
void save_mesh_ply(const std::string& path, const TriangleMesh& mesh);

}  // namespace vtloc::io
