#pragma once
// Large clouds (a depth camera's, a scanner's) reduced before the point
// branch: a voxel grid keeps one point per occupied voxel (the first in index
// order, so real measured points survive, normals with them) at about 4 x n
// voxels, then farthest point sampling (the fps op: on the GPU when a context
// is given) picks exactly n of those.
#include <cstdint>
#include <vector>

#include "engine/tensor.h"
#include "runtime/context.h"

namespace vtloc {

// Clouds of at least this many points are reduced by the API (smaller ones
// are used as they are, as before).
inline constexpr int64_t kReduceFromPoints = 100000;

// Farthest point sampling (the fps op, on the GPU when ctx is given, else its
// CPU reference): n row indices of cloud [N, D >= 3] from row 0; all rows, in
// order, when N <= n.
std::vector<int64_t> farthest_points(rt::Context* ctx, const HostTensor& cloud, int64_t n);

// cloud [N, D >= 3], finite xyz -> [n, D] rows of `cloud`; N <= n: unchanged.
HostTensor voxel_reduce(const HostTensor& cloud, int64_t target);  // about `target` rows, >= target when N >= target
HostTensor reduce_cloud(rt::Context* ctx, const HostTensor& cloud, int64_t n);

}  // namespace vtloc
