#pragma once
// Host-side helpers for the ops after the network (SPEC 3, 6): the symmetry
// prior's maps for the heatmap op, and the input checks the GPU cannot make.
#include <array>
#include <string>
#include <vector>

#include "engine/tensor.h"

namespace vtloc {

// The symmetry prior: `order` rotations by 360 m / order degrees (m = 0..order-1,
// right-handed about `axis_dir`) about the line through `axis_point` (normalised
// frame), as [order, 12] affine maps (3x4 row-major: R | a - R a), computed in
// double (shader cos/sin are too coarse). The heatmap op's optional 4th input.
HostTensor symmetry_transforms(const std::array<double, 3>& axis_point, const std::array<double, 3>& axis_dir,
                               int order);

// Throws naming `what` when t holds NaN or inf (the GPU ops would only propagate them).
void require_finite(const HostTensor& t, const std::string& what);

}  // namespace vtloc
