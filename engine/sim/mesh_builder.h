#pragma once
// Small builders for closed triangle meshes made of straight-edged parts:
// prisms from a 2D outline, solids of revolution, slabs and tubes whose
// surfaces are height fields on a tensor grid. Every builder returns a closed
// mesh wound outward (checked by the signed volume, so callers may give
// outlines and profiles in either direction). No vertex normals: the sampler
// then uses face normals, which keeps teeth and ridges sharp.
#include <cstdint>
#include <functional>
#include <vector>

#include "engine/io/mesh.h"

namespace vtloc::sim::mesh {

struct P2 {
    double x, y;
};

// Appends vertices and triangles; triangles of (near) zero area are dropped,
// which lets grids repeat a coordinate to make vertical walls.
class Builder {
public:
    uint32_t vertex(double x, double y, double z);
    void triangle(uint32_t a, uint32_t b, uint32_t c);
    void quad(uint32_t a, uint32_t b, uint32_t c, uint32_t d);  // split along a-c
    void append(const io::TriangleMesh& other);
    io::TriangleMesh finish();  // re-winds everything if the signed volume is negative

private:
    io::TriangleMesh m_;
};

// Signed volume (positive when a closed mesh is wound outward).
double signed_volume(const io::TriangleMesh& mesh);

// Ear-clipping triangulation of a simple polygon (either direction); indices
// into `poly`, each triangle counter-clockwise.
std::vector<uint32_t> triangulate_polygon(const std::vector<P2>& poly);

// Prism: a simple polygon in the xy-plane extruded from z0 to z1.
io::TriangleMesh extrude(const std::vector<P2>& outline, double z0, double z1);

// Solid of revolution about the z-axis: profile points (r, z) in order; an
// end with r == 0 is a pole, an end with r > 0 is closed by a flat disc.
io::TriangleMesh revolve(const std::vector<P2>& profile, int segments);

// Solid of revolution of a closed profile (r > 0 everywhere), e.g. a torus.
io::TriangleMesh revolve_closed(const std::vector<P2>& profile, int segments);

// Slab over the tensor grid xs x ys (non-decreasing; a repeated value gives a
// vertical step): top(i, j) and bottom(i, j) heights with top >= bottom,
// closed by vertical side walls. Each grid quad is split along the diagonal
// through its most extreme vertex, so pyramids on a half-step grid stay exact.
io::TriangleMesh slab(const std::vector<double>& xs, const std::vector<double>& ys,
                      const std::function<double(size_t, size_t)>& top,
                      const std::function<double(size_t, size_t)>& bottom);

// Tube about the z-axis: n_theta columns around, zs rows (non-decreasing),
// radius(i_theta, k) > 0, closed by flat end discs. Quads split as in slab.
io::TriangleMesh radial_tube(int n_theta, const std::vector<double>& zs,
                             const std::function<double(size_t, size_t)>& radius);

}  // namespace vtloc::sim::mesh
