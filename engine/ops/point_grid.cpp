#include "engine/ops/point_grid.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/ops/point_common.h"

namespace vtloc::ops {

PointGrid build_point_grid(const HostTensor& xyz, int64_t k) {
    if (xyz.shape.size() != 2 || xyz.shape[1] < 3) throw Error("points must be [N, D >= 3], got " + shape_str(xyz.shape));
    const int64_t N = xyz.shape[0], D = xyz.shape[1];
    if (N == 0) throw Error("the point cloud is empty");
    require_finite_xyz(xyz, "point grid");
    std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (int64_t i = 0; i < N; ++i)
        for (int a = 0; a < 3; ++a) {
            const double v = xyz.data[size_t(i * D + a)];
            lo[size_t(a)] = std::min(lo[size_t(a)], v);
            hi[size_t(a)] = std::max(hi[size_t(a)], v);
        }
    std::array<double, 3> ext{};
    for (int a = 0; a < 3; ++a) ext[size_t(a)] = hi[size_t(a)] - lo[size_t(a)];
    const double big = std::max({ext[0], ext[1], ext[2]});
    // A surface's area is of the order of the bounding box's largest faces.
    const double area = std::max({ext[0] * ext[1], ext[1] * ext[2], ext[0] * ext[2], 1e-30});
    double cell = std::sqrt(area * double(std::max<int64_t>(k, 1)) / double(N));
    cell = std::max(cell, big / 64.0);
    if (!(cell > 0) || !std::isfinite(cell)) cell = 1;  // all points identical: one cell
    PointGrid g;
    g.cell = cell;
    g.origin = lo;
    for (int a = 0; a < 3; ++a)
        g.dims[size_t(a)] = std::max<int64_t>(1, int64_t(std::floor(ext[size_t(a)] / cell)) + 1);
    const int64_t G = g.dims[0] * g.dims[1] * g.dims[2];
    std::vector<int32_t> cell_of(static_cast<size_t>(N)), start(static_cast<size_t>(G + 1), 0),
        order(static_cast<size_t>(N));
    for (int64_t i = 0; i < N; ++i) {
        int64_t c[3];
        for (int a = 0; a < 3; ++a) {
            // the same float arithmetic as the shader's cell lookup (cell_coord in normal_estimate.comp)
            const float rel = (xyz.data[size_t(i * D + a)] - float(lo[size_t(a)])) / float(cell);
            c[a] = std::clamp<int64_t>(int64_t(std::floor(rel)), 0, g.dims[size_t(a)] - 1);
        }
        cell_of[size_t(i)] = int32_t((c[2] * g.dims[1] + c[1]) * g.dims[0] + c[0]);
        ++start[size_t(cell_of[size_t(i)]) + 1];
    }
    for (int64_t c = 0; c < G; ++c) start[size_t(c + 1)] += start[size_t(c)];
    std::vector<int32_t> fill(start.begin(), start.end() - 1);
    for (int64_t i = 0; i < N; ++i) order[size_t(fill[size_t(cell_of[size_t(i)])]++)] = int32_t(i);
    g.order = HostTensor::from_ints({N}, order);
    g.cell_start = HostTensor::from_ints({G + 1}, start);
    return g;
}

void set_grid_params(Params& p, const PointGrid& g) {
    p.set("gx", double(g.dims[0])).set("gy", double(g.dims[1])).set("gz", double(g.dims[2]));
    p.set("cell", g.cell).set("ox", g.origin[0]).set("oy", g.origin[1]).set("oz", g.origin[2]);
}

}  // namespace vtloc::ops
