#pragma once
// Builders for the everyday objects' curved parts (engine/sim/everyday_shapes.cpp),
// beside mesh_builder.h's straight-edged ones: lofts through rings of points,
// flat parts with holes and rounded rims whose thickness and mid-surface vary
// (cutlery, keys, wrenches), and a join of closed parts.
// Every builder returns a closed mesh wound outward, without vertex normals.
#include <functional>
#include <vector>

#include "engine/io/mesh.h"
#include "engine/sim/mesh_builder.h"

namespace vtloc::sim::mesh {

struct P3 {
    double x, y, z;
};

// Closed mesh through rings of points: every ring a closed loop of the same
// size, all going the same way round; ring k joins ring k + 1 by quads. An end
// ring whose points all coincide is a pole; any other is closed by its
// (near-planar) polygon.
io::TriangleMesh loft(const std::vector<std::vector<P3>>& rings);

// Triangles (indices into outer followed by each hole in turn, counter-clockwise)
// of a simple polygon with simple holes inside it, by bridging each hole to the
// outline and ear clipping. Outline and holes may be given in either direction.
std::vector<uint32_t> triangulate_with_holes(const std::vector<P2>& outer, const std::vector<std::vector<P2>>& holes);

// The closed loops where f(x, y) changes sign (f < 0 inside), by marching
// squares over lo..hi every `step` (f must be positive on the box's border),
// simplified to within `tolerance` (Douglas-Peucker): outlines come
// counter-clockwise, holes clockwise. Lets an outline be drawn as a 2D signed
// distance: unions, cuts and fillets of circles, capsules and polygons.
std::vector<std::vector<P2>> contour_loops(const std::function<double(double, double)>& f, P2 lo, P2 hi, double step,
                                           double tolerance = 0.004);

// An open polyline with corner i replaced by a tangent arc of radius[i] in
// `segments` steps (0: kept sharp; a radius too big for its edges is reduced
// to fit half of each). For revolve profiles.
std::vector<P2> rounded(const std::vector<P2>& polyline, const std::vector<double>& radius, int segments = 8);

// A flat part: the region shape(x, y) < 0 (a 2D signed distance, outlines and
// holes alike) inside the box lo..hi, traced every `step` mm, its rim rounded by
// a half ellipse of in-plane radius edge_radius(x, y), its faces triangulated
// and refined until no edge is longer than max_edge(x, y) (measured with the
// part nominal_thickness thick), then shaped: a point at fraction f in [-1, 1]
// of the way up moves to centre(x, y) + f * thickness(x, y) / 2.
struct SheetSpec {
    std::function<double(double, double)> shape;
    P2 lo{0, 0}, hi{0, 0};
    double step = 0.1;
    std::function<double(double, double)> edge_radius = [](double, double) { return 0.5; };
    int edge_segments = 6;
    double nominal_thickness = 2;
    std::function<double(double, double)> max_edge = [](double, double) { return 1.0; };
    std::function<double(double, double)> max_edge_bottom;
    std::function<double(double, double)> thickness = [](double, double) { return 2.0; };
    std::function<double(double, double)> centre = [](double, double) { return 0.0; };
};
io::TriangleMesh sheet(const SheetSpec& spec);

// Every vertex moved by f; triangles re-wound if that turned the mesh inside out.
io::TriangleMesh moved(io::TriangleMesh mesh, const std::function<P3(const P3&)>& f);

// Closed parts side by side in one mesh, each keeping its own vertices: parts
// may overlap (the touch renderer keeps the nearest surface), and a part
// never shares an edge with another, so each stays closed on its own.
io::TriangleMesh join(const std::vector<io::TriangleMesh>& parts);

}  // namespace vtloc::sim::mesh
