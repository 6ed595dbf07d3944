#pragma once
// A depth camera's view of the object as a point cloud (partial, no normals):
// each pixel with a measurement (inside the mask, when one is given) back-
// projected with the pinhole intrinsics.
#include <string>

#include "engine/tensor.h"

namespace vtloc::io {

struct CameraIntrinsics {
    double fx = 0, fy = 0, cx = 0, cy = 0;  // pixels
};

// depth_path: 16-bit PNG, value * unit_mm = depth in mm, 0 = none. mask_path:
// "" or an image of the same size. -> N x 3, camera frame (x right, y down,
// z forward), mm: p = ((u - cx) z / fx, (v - cy) z / fy, z) at pixel
// (u, v) = (column, row), as OpenCV and RealSense intrinsics count. Throws
// naming the file: wrong pixel type, a mask of
// another size, bad intrinsics or unit, no pixel with a measurement.
HostTensor depth_to_cloud(const std::string& depth_path, const CameraIntrinsics& k, const std::string& mask_path = "",
                          double unit_mm = 1.0);

}  // namespace vtloc::io
