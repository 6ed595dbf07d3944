// Heat for display points (see render.h): a brute-force nearest-point lookup,
// apart from the renderer since it needs no OpenCV.
#include <string>

#include "base/error.h"
#include "engine/io/render.h"

namespace vtloc::io {

std::vector<float> nearest_heat(const HostTensor& cloud, std::span<const float> heat, const HostTensor& points) {
    auto rows = [](const HostTensor& t) { return t.shape.size() == 2 && (t.shape[1] == 3 || t.shape[1] == 6); };
    if (!rows(cloud) || !rows(points) || size_t(cloud.shape[0]) != heat.size() || cloud.shape[0] < 1)
        throw Error("nearest_heat: cloud " + shape_str(cloud.shape) + " with " + std::to_string(heat.size()) +
                    " heat values, points " + shape_str(points.shape));
    const size_t n = size_t(cloud.shape[0]), cw = size_t(cloud.shape[1]), pw = size_t(points.shape[1]);
    std::vector<float> out(size_t(points.shape[0]));
    for (size_t i = 0; i < out.size(); ++i) {
        const float* p = &points.data[i * pw];
        double best = 1e300;
        for (size_t j = 0; j < n; ++j) {
            const float* q = &cloud.data[j * cw];
            double d = (double(p[0]) - q[0]) * (double(p[0]) - q[0]) + (double(p[1]) - q[1]) * (double(p[1]) - q[1]) +
                       (double(p[2]) - q[2]) * (double(p[2]) - q[2]);
            if (d < best) best = d, out[i] = heat[j];
        }
    }
    return out;
}

}  // namespace vtloc::io
