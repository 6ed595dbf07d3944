#pragma once
// Folds an eval-mode BatchNorm into the convolution or linear layer before it,
// once at load time, so no BN op ever runs:
//   W'[o, ...] = W[o, ...] * g[o],  b'[o] = (b[o] - mean[o]) * g[o] + beta[o],
//   g[o] = gamma[o] / sqrt(var[o] + eps).
#include <string>

#include "engine/weights.h"

namespace vtloc {

struct FoldedNames {
    std::string weight, bias;
};

// Reads `<layer>.weight` (and `<layer>.bias` if present) and
// `<bn>.{weight,bias,running_mean,running_var}`; adds the folded tensors to
// `w` under new names (returned) and leaves the originals in place.
FoldedNames fold_batchnorm(WeightStore& w, const std::string& layer, const std::string& bn, double eps = 1e-5);

}  // namespace vtloc
