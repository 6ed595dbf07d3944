#include "engine/model/cloud_reduce.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "base/error.h"
#include "engine/executor.h"
#include "engine/graph.h"
#include "engine/ops/build.h"

namespace vtloc {

namespace {

// Rows of `cloud` that are the first of their voxel (edge `size`), in index order.
std::vector<int64_t> voxel_firsts(const HostTensor& cloud, double size, const double lo[3]) {
    const int64_t N = cloud.shape[0], D = cloud.shape[1];
    std::unordered_set<uint64_t> seen;
    seen.reserve(size_t(N));
    std::vector<int64_t> keep;
    for (int64_t i = 0; i < N; ++i) {
        uint64_t key = 0;
        for (int a = 0; a < 3; ++a)  // 21 bits a side: a voxel grid of up to 2M cells per axis
            key = key << 21 | (uint64_t(std::floor((cloud.data[size_t(i * D + a)] - lo[a]) / size)) & 0x1FFFFF);
        if (seen.insert(key).second) keep.push_back(i);
    }
    return keep;
}

}  // namespace

std::vector<int64_t> farthest_points(rt::Context* ctx, const HostTensor& cloud, int64_t n) {
    std::vector<int64_t> out;
    if (cloud.shape[0] <= n) {
        for (int64_t i = 0; i < cloud.shape[0]; ++i) out.push_back(i);
        return out;
    }
    Graph g;
    const int x = g.input("cloud", cloud.shape);
    const std::vector<int> f = ops::fps(g, x, n, "fps");
    g.output(f[0], "index");
    const TensorMap in{{"cloud", cloud}};
    const HostTensor idx = ctx ? GpuExecutor(*ctx, g, WeightStore{}).run(in).at("index")
                               : run_cpu(g, WeightStore{}, in).at("index");
    for (int64_t r = 0; r < n; ++r) out.push_back(idx.int_at(size_t(r)));
    return out;
}

HostTensor voxel_reduce(const HostTensor& cloud, int64_t target) {
    const int64_t N = cloud.shape[0], D = cloud.shape[1];
    if (N <= target) return cloud;
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (int64_t i = 0; i < N; ++i)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], double(cloud.data[size_t(i * D + a)]));
            hi[a] = std::max(hi[a], double(cloud.data[size_t(i * D + a)]));
        }
    const double ext = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-30});
    // Bisect the voxel edge (log scale) for the largest one that keeps >= target points.
    double small = ext / 2e6, big = ext;  // 2e6 cells a side keeps every distinct point
    std::vector<int64_t> keep = voxel_firsts(cloud, small, lo);
    if (int64_t(keep.size()) >= target)
        for (int round = 0; round < 24; ++round) {
            const double mid = std::sqrt(small * big);
            std::vector<int64_t> k = voxel_firsts(cloud, mid, lo);
            if (int64_t(k.size()) >= target) {
                small = mid;
                keep = std::move(k);
            } else {
                big = mid;
            }
            if (big / small < 1.02) break;
        }
    HostTensor out({int64_t(keep.size()), D});
    for (size_t r = 0; r < keep.size(); ++r)
        std::copy_n(&cloud.data[size_t(keep[r] * D)], size_t(D), &out.data[r * size_t(D)]);
    return out;
}

HostTensor reduce_cloud(rt::Context* ctx, const HostTensor& cloud, int64_t n) {
    if (cloud.shape.size() != 2 || cloud.shape[1] < 3) throw Error("reduce_cloud: points must be [N, >= 3]");
    if (n < 1) throw Error("reduce_cloud: n must be >= 1");
    if (cloud.shape[0] <= n) return cloud;
    const HostTensor pre = voxel_reduce(cloud, 4 * n);
    if (pre.shape[0] <= n) return pre;  // fewer distinct points than n
    const std::vector<int64_t> idx = farthest_points(ctx, pre, n);
    const int64_t D = pre.shape[1];
    HostTensor out({n, D});
    for (int64_t r = 0; r < n; ++r)
        std::copy_n(&pre.data[size_t(idx[size_t(r)] * D)], size_t(D), &out.data[size_t(r * D)]);
    return out;
}

}  // namespace vtloc
