#pragma once
// A single view of an object as a depth camera sees it: the surface visible
// from one direction (orthographic, i.e. a camera far away), sampled on a
// pixel grid over the object's bounding sphere and reduced to n points by
// farthest point sampling. No normals: a robot's camera gives none.
#include <array>
#include <cstdint>
#include <filesystem>

#include "engine/io/mesh.h"
#include "engine/tensor.h"

namespace vtloc::sim {

struct PartialView {
    HostTensor xyz;                    // [n, 3] object units (fewer when fewer pixels see the object)
    std::array<double, 3> direction{}; // the viewing direction (camera -> object), unit
    std::array<double, 3> camera{};    // a point on the camera side, 10 diameters away (orients normals)
    int visible_pixels = 0;
};

// Direction uniform on the sphere from `seed`; `pixels` x `pixels` rays.
PartialView render_partial_view(const io::TriangleMesh& mesh, uint64_t seed, int n_points, int pixels = 160);

// view.xyz (x y z rows) and view.json (camera, direction, counts) in `dir`,
// each written to a temporary name and renamed.
void write_partial_view(const std::filesystem::path& dir, const PartialView& view);

// Both files in place: a run killed between the two renames leaves view.xyz alone
// (and view.json.tmp, which the next write_partial_view renames).
bool has_partial_view(const std::filesystem::path& dir);

}  // namespace vtloc::sim
