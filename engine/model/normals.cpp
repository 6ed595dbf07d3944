#include "engine/model/normals.h"

#include <cmath>
#include <vector>

#include "base/error.h"
#include "engine/executor.h"
#include "engine/graph.h"
#include "engine/ops/build.h"
#include "engine/ops/object_frame.h"
#include "engine/ops/point_grid.h"

namespace vtloc {

HostTensor estimate_normals(rt::Context* ctx, const HostTensor& xyz, const NormalOptions& o) {
    if (xyz.shape.size() != 2 || xyz.shape[1] < 3)
        throw Error("normal estimation: points must be [N, >= 3], got " + shape_str(xyz.shape));
    const int64_t N = xyz.shape[0], D = xyz.shape[1];
    if (N < o.k)
        throw Error("normal estimation needs at least " + std::to_string(o.k) + " points (its neighbourhood size), got " +
                    std::to_string(N));
    const ops::PointGrid grid = ops::build_point_grid(xyz, o.k);  // also checks the points are finite
    // Towards the camera when one is given, else away from the centroid (as SPEC 1's frame has it).
    const int orient = o.towards ? 2 : 1;
    const std::array<double, 3> ref = o.towards ? *o.towards : object_frame(xyz, "normal estimation").centre;
    Graph g;
    const int x = g.input("points", xyz.shape);
    const int order = g.input("order", grid.order.shape, ElemType::I32);
    const int start = g.input("cell_start", grid.cell_start.shape, ElemType::I32);
    g.output(ops::normal_estimate(g, x, order, start, grid, o.k, orient, ref, "normals"), "normals");
    const TensorMap in{{"points", xyz}, {"order", grid.order}, {"cell_start", grid.cell_start}};
    const HostTensor n = ctx ? GpuExecutor(*ctx, g, WeightStore{}).run(in).at("normals")
                             : run_cpu(g, WeightStore{}, in).at("normals");
    HostTensor out({N, 6});
    std::vector<int64_t> valid, degenerate;
    for (int64_t i = 0; i < N; ++i) {
        (std::isfinite(n.data[size_t(i * 3)]) ? valid : degenerate).push_back(i);
        for (int a = 0; a < 3; ++a) {
            out.data[size_t(i * 6 + a)] = xyz.data[size_t(i * D + a)];
            out.data[size_t(i * 6 + 3 + a)] = n.data[size_t(i * 3 + a)];
        }
    }
    if (valid.empty())
        throw Error("normal estimation: no point has a normal: every point's " + std::to_string(o.k) +
                    " nearest points are collinear or identical (a line, or one point repeated)");
    // A degenerate neighbourhood (a thin wire, one scan line of a depth view) takes
    // the normal of the nearest point that has one (lowest index on a tie).
    for (int64_t i : degenerate) {
        const float* p = &xyz.data[size_t(i * D)];
        int64_t best = valid[0];
        double best_d = INFINITY;
        for (int64_t j : valid) {
            const float* q = &xyz.data[size_t(j * D)];
            const double d = double(p[0] - q[0]) * (p[0] - q[0]) + double(p[1] - q[1]) * (p[1] - q[1]) +
                             double(p[2] - q[2]) * (p[2] - q[2]);
            if (d < best_d) best_d = d, best = j;
        }
        for (int a = 0; a < 3; ++a) out.data[size_t(i * 6 + 3 + a)] = n.data[size_t(best * 3 + a)];
    }
    return out;
}

}  // namespace vtloc
