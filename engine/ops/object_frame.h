#pragma once
// The normalised frame of SPEC section 1 (the model's host normalisation and
// the cloud_normalize op's CPU oracle): centre = mean(xyz), scale = max
// ||p - centre||. Computed on the host in double and rounded once to float,
// exactly as the PyTorch reference does, so FPS and ball query see bit-equal
// coordinates and pick the same indices.
#include <array>
#include <string>

#include "engine/tensor.h"

namespace vtloc {

struct ObjectFrame {
    std::array<double, 3> centre{0, 0, 0};
    double scale = 1.0;
};

// cloud: [N, D >= 3], object units. Throws (naming `what`) on an empty cloud,
// NaN/inf coordinates, or all points identical (no scale).
ObjectFrame object_frame(const HostTensor& cloud, const std::string& what = "object cloud");

// [M, D >= 3] -> [M, keep]: xyz mapped to the frame, columns 3..keep-1 copied
// unchanged (normals are not scaled). keep is 3 or D.
HostTensor to_frame(const HostTensor& points, const ObjectFrame& f, int64_t keep);

// Back to object units.
std::array<double, 3> from_frame(const float* p, const ObjectFrame& f);

}  // namespace vtloc
