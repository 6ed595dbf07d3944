#pragma once
// The object point cloud P of SPEC section 1 (N x 6: xyz in object units,
// unit normals) from a mesh or a point-cloud file.
#include <cstdint>
#include <string>

#include "engine/io/mesh.h"
#include "engine/tensor.h"

namespace vtloc::io {

// Checks a cloud in place: N x 6, every value finite, no zero normal; normals
// whose length is not 1 (off by more than 1e-4) are scaled to unit length,
// exactly unit ones are left bit for bit. Throws vtloc::Error naming `source`
// and the first bad point's index.
void check_cloud(HostTensor& cloud, const std::string& source);

// A PLY point cloud with normals (x y z nx ny nz by name, any numeric type,
// other properties skipped), checked by check_cloud.
HostTensor load_ply_cloud(const std::string& path);

// By extension: .glb / .gltf meshes are sampled to n_points (sample_surface
// with `seed`); .ply clouds are read as they are, whatever their size (use
// require_points for the model's count).
HostTensor load_object(const std::string& path, int64_t n_points, uint64_t seed = kDefaultSampleSeed);

// Throws "<source>: the object has K points, the model needs at least N" when
// the cloud is smaller than `needed`.
void require_points(const HostTensor& cloud, int64_t needed, const std::string& source);

}  // namespace vtloc::io
