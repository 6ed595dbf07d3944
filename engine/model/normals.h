#pragma once
// Normals for a cloud that has none (an RGB-D view, a PLY/PCD/XYZ without
// nx ny nz): the normal_estimate op on the GPU (or its CPU reference), with
// the grid built on the host. A degenerate neighbourhood is an error naming
// the point.
#include <array>
#include <optional>

#include "engine/tensor.h"
#include "runtime/context.h"

namespace vtloc {

struct NormalOptions {
    int k = 16;  // neighbours, the point itself included (3..32)
    // Oriented towards this point (a camera's position) when given, else away
    // from the cloud's centroid.
    std::optional<std::array<double, 3>> towards;
};

// xyz [N, >= 3] (finite) -> [N, 6]: xyz and unit normals. ctx null: CPU reference.
HostTensor estimate_normals(rt::Context* ctx, const HostTensor& xyz, const NormalOptions& options = {});

}  // namespace vtloc
