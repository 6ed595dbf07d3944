#pragma once
// A uniform grid over a point cloud, built on the host in O(N) (counting sort):
// the spatial index normal_estimate searches (k nearest neighbours ring by ring
// instead of an O(N^2) scan). Its geometry travels to the op as parameters.
#include <array>
#include <cstdint>

#include "engine/graph.h"
#include "engine/tensor.h"

namespace vtloc::ops {

struct PointGrid {
    std::array<double, 3> origin{};   // lower corner
    double cell = 1;                  // edge length
    std::array<int64_t, 3> dims{1, 1, 1};
    HostTensor order;       // I32 [N]: point indices sorted by cell (stable: index order within a cell)
    HostTensor cell_start;  // I32 [G + 1]: cell c holds order[cell_start[c] .. cell_start[c + 1])
};

// Cells of ~k points for a surface sample: cell = sqrt(area estimate * k / N),
// the area estimated from the bounding box; at most 64 cells a side.
// xyz: [N, D >= 3], finite (throws otherwise, naming the point).
PointGrid build_point_grid(const HostTensor& xyz, int64_t k);

// The grid's geometry as normal_estimate parameters (gx gy gz cell ox oy oz).
void set_grid_params(Params& p, const PointGrid& g);

}  // namespace vtloc::ops
