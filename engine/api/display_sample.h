#pragma once
// An evenly spaced sample of a mesh's surface for pictures. Plain random
// samples clump and leave holes between the render's discs; thinning a
// random sample so that no two points are closer than r (Poisson-disc) gives
// a surface that reads as solid. For display only: the model's cloud is
// io::sample_surface's.
#include <string>

#include "engine/io/mesh.h"
#include "engine/tensor.h"

namespace vtloc::api {

// About n points (x y z nx ny nz), deterministic.
HostTensor display_sample(const io::TriangleMesh& mesh, int64_t n, const std::string& source);

}  // namespace vtloc::api
