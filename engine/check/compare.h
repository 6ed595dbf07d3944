#pragma once
// Comparing a GPU tensor with its CPU reference: fp32 within
// |gpu - cpu| <= abs + rel * |cpu| elementwise, I32 (index) tensors exactly.
// Shared by the model check and the op self-test (engine/check/).
#include <cstdint>
#include <string>

#include "engine/tensor.h"

namespace vtloc::check {

struct Tolerance {
    double abs = 1e-4;
    double rel = 1e-4;
};
inline constexpr Tolerance kNodeTolerance{1e-4, 1e-4};     // one op against its reference
inline constexpr Tolerance kEndToEndTolerance{2e-3, 2e-3};  // the whole model, errors accumulated

struct Comparison {
    bool index = false;         // I32: compared exactly
    bool ok = true;
    double max_abs = 0;         // max |gpu - cpu| (index tensors: 0 when equal)
    double max_rel = 0;         // max |gpu - cpu| / |cpu| over elements with |cpu| > tol.abs
    double worst_ratio = 0;     // max |gpu - cpu| / (abs + rel * |cpu|); > 1 fails
    int64_t mismatches = 0;     // elements out of tolerance (or unequal indices)
    int64_t first_bad = -1;     // flat index of the first such element
    std::string detail;         // the first bad element, when there is one
};

// Shapes and types must agree (a difference is a failed comparison, not a throw).
// A NaN on one side only fails; NaN on both sides is equal.
Comparison compare(const HostTensor& gpu, const HostTensor& cpu, Tolerance tol);

// Merges b into a (max of the errors, sum of mismatches, first failure kept).
void merge(Comparison& a, const Comparison& b);

}  // namespace vtloc::check
