#include "engine/io/depth.h"

#include "base/error.h"

#include <cmath>
#include <vector>

#include "engine/io/file_bytes.h"
#include "engine/io/image.h"

namespace vtloc::io {

HostTensor depth_to_cloud(const std::string& depth_path, const CameraIntrinsics& k, const std::string& mask_path,
                          double unit_mm) {
    if (!(k.fx > 0) || !(k.fy > 0) || !std::isfinite(k.fx) || !std::isfinite(k.fy) || !std::isfinite(k.cx) ||
        !std::isfinite(k.cy))
        fail(depth_path, "bad camera intrinsics (fx, fy must be finite and > 0; cx, cy finite)");
    if (!(unit_mm > 0) || !std::isfinite(unit_mm)) fail(depth_path, "the depth unit must be a finite number > 0 (mm)");
    const DepthImage d = load_depth_image(depth_path);
    MaskImage m;
    if (!mask_path.empty()) {
        m = load_mask_image(mask_path);
        if (m.height != d.height || m.width != d.width)
            fail(mask_path, "the mask is " + std::to_string(m.width) + "x" + std::to_string(m.height) +
                                ", the depth image " + std::to_string(d.width) + "x" + std::to_string(d.height));
    }
    std::vector<float> xyz;
    for (int v = 0; v < d.height; ++v)
        for (int u = 0; u < d.width; ++u) {
            const size_t i = size_t(v) * size_t(d.width) + size_t(u);
            if (d.depth[i] == 0 || (!m.on.empty() && !m.on[i])) continue;
            const double z = double(d.depth[i]) * unit_mm;
            xyz.push_back(float((double(u) - k.cx) * z / k.fx));
            xyz.push_back(float((double(v) - k.cy) * z / k.fy));
            xyz.push_back(float(z));
        }
    if (xyz.empty())
        fail(depth_path, mask_path.empty() ? "no pixel has a depth measurement" : "no pixel inside the mask has a depth measurement");
    const int64_t n = int64_t(xyz.size() / 3);
    return HostTensor({n, 3}, std::move(xyz));
}

}  // namespace vtloc::io
