#pragma once
// Simple analytic meshes for the renderer's tests and its reality check:
// a finely tessellated sphere and a flat rectangle. Units are the caller's
// (mm for the renderer). Counter-clockwise seen from outside / from +z.
#include <array>

#include "engine/io/mesh.h"

namespace vtloc::sim {

// Icosahedron subdivided `subdivisions` times (20 * 4^s triangles), vertices
// on the sphere, per-vertex normals. s = 5 gives 20480 triangles: edges of
// 0.035 * radius, so a 2 mm ball is faceted well below a 0.12 mm pixel.
// Throws vtloc::Error for radius <= 0 or subdivisions outside 0..8.
io::TriangleMesh make_icosphere(double radius, int subdivisions, const std::array<double, 3>& centre = {0, 0, 0});

// The rectangle [-sx/2, sx/2] x [-sy/2, sy/2] at z = 0, normal +z, as an
// nx x ny grid of quads (two triangles each). Throws for sizes <= 0 or
// cells outside 1..4096.
io::TriangleMesh make_plane(double size_x, double size_y, int nx = 1, int ny = 1);

}  // namespace vtloc::sim
