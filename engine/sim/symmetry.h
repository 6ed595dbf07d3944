#pragma once
// Rigid symmetries of an object (SPEC 6's metrics: ND up to symmetry): a group
// of proper rotations about an axis through `point`, cyclic of `order` (0: every
// angle), and with `flip` a 2-fold axis perpendicular to it through the same
// point (the dihedral group); or, with `all`, every rotation about `point` (a
// sphere: no touch can tell two of its points apart). Declared by the procedural shapes (in their own
// frame, moved with the builder's scaling) and stored in object.json
// ("symmetry", docs/dataset.md). A declaration is accepted only where the mesh
// maps onto itself within 0.2 mm (symmetry_residual_mm).
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "engine/io/mesh.h"

namespace vtloc::sim {

using Vec3d = std::array<double, 3>;
using Mat3d = std::array<double, 9>;  // row-major

struct Symmetry {
    Vec3d point{}, axis{0, 0, 1};
    int order = 1;                 // 1: no rotation about the axis; 0: every angle
    std::optional<Vec3d> flip;     // a 2-fold axis perpendicular to `axis`
    bool all = false;              // every rotation about `point` (axis, order and flip unused)
    bool none() const { return !all && order == 1 && !flip; }
    // Every element (the identity first); an order of 0 is taken as 360 steps of
    // 1 degree (a point at radius r is then within r * 0.0088 of its nearest copy);
    // `all` as 24 steps about each of x, y, z and (1, 1, 1) (a sample, for the check).
    std::vector<Mat3d> rotations() const;
    Vec3d apply(const Mat3d& R, const Vec3d& p) const;  // rotation about `point`
};

nlohmann::json symmetry_json(const Symmetry& s);  // null for none
// Throws vtloc::Error naming `where` for a malformed entry (non-unit-able axis,
// negative order, a flip axis not perpendicular within 1e-3).
Symmetry symmetry_from_json(const nlohmann::json& j, const std::string& where);

// The group of a procedural shape in its own frame (none where it has none).
Symmetry shape_symmetry(const std::string& name);
// The same group after the builder's x' = f (x - centre).
Symmetry scaled_symmetry(const Symmetry& s, double f, const Vec3d& centre);

// The distance from `pred` to the nearest image of `truth` under the group
// (exact for every angle: the circles the two points sweep).
double distance_up_to_symmetry(const Symmetry& s, const Vec3d& pred, const Vec3d& truth);

// The largest distance (mm) from a rotated surface sample to the mesh over every
// element (a continuous group: 24 angles), on `samples` points.
double symmetry_residual_mm(const Symmetry& s, const io::TriangleMesh& mesh, int samples = 1500);

}  // namespace vtloc::sim
