#pragma once
// Normals for a cloud that has none (an RGB-D view, a PLY/PCD/XYZ without
// nx ny nz): the normal_estimate op on the GPU (or its CPU reference), with
// the grid built on the host. A point whose neighbourhood is degenerate
// (collinear or identical: a thin wire, one scan line of a depth view) takes
// the normal of the nearest point that has one; a cloud where no point has one
// (a line, one point repeated) is an error.
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
