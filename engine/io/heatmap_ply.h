#pragma once
// The heat-map as a PLY file that any point-cloud viewer (MeshLab,
// CloudCompare, Open3D) shows in colour.
#include <span>
#include <string>

#include "engine/io/ply.h"
#include "engine/tensor.h"

namespace vtloc::io {

// cloud: N x 6 (xyz, normal) or N x 3; heat: N values in [0, 1] (SPEC
// section 3). Writes x y z [nx ny nz] contact_prob red green blue, the
// colour from heat_color().
void write_heatmap_ply(const std::string& path, const HostTensor& cloud, std::span<const float> heat,
                       PlyFormat format = PlyFormat::BinaryLittleEndian);

}  // namespace vtloc::io
