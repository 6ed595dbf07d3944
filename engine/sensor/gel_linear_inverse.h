#pragma once
// The calibration's shading linearised about the untouched gel, inverted per pixel: for gentle
// slopes (a large object pressed a millimetre) the colour change is a few grey levels, below
// the gradient tables' 8-level cells, but near-linear in the slope. Op gel_gradient uses it
// where the tables' slope is gentle (docs/gel_shape.md).
#include <vector>

#include "engine/sensor/calibration.h"

namespace vtloc::sensor {

// [H, W, 6]: per pixel the 2 x 3 matrix L (row-gradient row, then column-gradient row) with
// g ~= L (frame - empty): the least-squares inverse of the 3 x 2 Jacobian J of the shading at the
// untouched gel's slope (depth_bg), J fitted over slopes up to `max_slope` (6 rings of 36).
// Rows on up to `threads` host threads (0: up to 4); the same bits on any number.
inline constexpr double kLinearMaxSlope = 0.3;
std::vector<float> build_linear_inverse(const Calibration& c, double max_slope = kLinearMaxSlope, int threads = 0);

}  // namespace vtloc::sensor
