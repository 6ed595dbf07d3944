#pragma once
// SPEC section 5's subset rule: for every point of the normalised cloud take
// its nearest neighbour j, dn = ||n_j - n_i|| / ||p_j - p_i||; the object is
// non-uniform when fewer than 70 % of its points have dn < 30.
#include "engine/tensor.h"

namespace vtloc::sim {

struct Uniformity {
    double share_below = 0;   // fraction of points with dn < 30
    bool uniform = true;      // share_below >= 0.7
};

// cloud: N x 6 in object units (normalised here: centre = mean, scale = max
// distance from it). Coincident neighbours (distance 0) count as dn = inf
// unless their normals are equal (then dn = 0).
Uniformity measure_uniformity(const HostTensor& cloud);

}  // namespace vtloc::sim
