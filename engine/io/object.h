#pragma once
// The object point cloud P of SPEC section 1 (N x 6: xyz in object units,
// unit normals) from a mesh or a point-cloud file.
#include <cstdint>
#include <string>

#include "engine/io/mesh.h"
#include "engine/tensor.h"

namespace vtloc::io {

// Checks a cloud in place: N x 3 (xyz) or N x 6 (xyz, normal), not empty,
// every value finite, no zero normal; normals whose length is not 1 (off by
// more than 1e-4) are scaled to unit length, exactly unit ones are left bit
// for bit. Throws vtloc::Error naming `source` and the first bad point's index.
void check_cloud(HostTensor& cloud, const std::string& source);

// A PLY point cloud with normals (x y z nx ny nz by name, any numeric type,
// other properties skipped), checked by check_cloud.
HostTensor load_ply_cloud(const std::string& path);

// By extension: meshes (.glb .gltf .obj .off .stl, and .ply with a face
// element) are sampled to n_points (sample_surface with `seed`): N x 6.
// Point clouds are read as they are, whatever their size (use require_points
// for the model's count): N x 6 when the file has normals (.ply nx ny nz,
// text rows of six values, checked by check_cloud), N x 3 when it has none
// (.ply without normals, .pcd, text rows of three): estimate them then
// (engine/model/normals.h). The result has passed check_cloud.
HostTensor load_object(const std::string& path, int64_t n_points, uint64_t seed = kDefaultSampleSeed);


// A PCD file as PCL writes it (DATA ascii or binary; binary_compressed is
// refused with a clear error): fields x y z, and normal_x normal_y normal_z
// when present (then N x 6), other fields skipped; any SIZE/TYPE/COUNT.
// Points with a NaN coordinate (PCL's "no measurement" in organised clouds)
// are dropped; a cloud left empty is an error. Not checked further: load_object
// runs check_cloud on it.
HostTensor load_pcd(const std::string& path);

// Throws "<source>: the object has K points, the model needs at least N" when
// the cloud is smaller than `needed`.
void require_points(const HostTensor& cloud, int64_t needed, const std::string& source);

}  // namespace vtloc::io
