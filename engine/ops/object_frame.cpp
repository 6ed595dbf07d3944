#include "engine/ops/object_frame.h"

#include <cmath>

#include "base/error.h"

namespace vtloc {

ObjectFrame object_frame(const HostTensor& cloud, const std::string& what) {
    if (cloud.shape.size() != 2 || cloud.shape[1] < 3)
        throw Error(what + " must be [N, 3] or [N, 6], got " + shape_str(cloud.shape));
    const int64_t n = cloud.shape[0], d = cloud.shape[1];
    if (n == 0) throw Error(what + " is empty");
    ObjectFrame f;
    for (int64_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            float v = cloud.data[size_t(i * d + c)];
            if (!std::isfinite(v))
                throw Error(what + ": point " + std::to_string(i) + " has a NaN or infinite coordinate");
            f.centre[size_t(c)] += v;
        }
    for (double& c : f.centre) c /= double(n);
    double max2 = 0.0;
    for (int64_t i = 0; i < n; ++i) {
        double s = 0.0;
        for (int c = 0; c < 3; ++c) {
            double e = double(cloud.data[size_t(i * d + c)]) - f.centre[size_t(c)];
            s += e * e;
        }
        max2 = std::max(max2, s);
    }
    f.scale = std::sqrt(max2);
    if (!(f.scale > 0.0)) throw Error(what + ": all points are identical, so it has no size to normalise by");
    return f;
}

HostTensor to_frame(const HostTensor& points, const ObjectFrame& f, int64_t keep) {
    const int64_t m = points.shape.at(0), d = points.shape.at(1);
    if (keep != 3 && keep != d) throw Error("to_frame: cannot keep " + std::to_string(keep) + " of " + std::to_string(d) + " columns");
    HostTensor out({m, keep});
    for (int64_t i = 0; i < m; ++i) {
        for (int c = 0; c < 3; ++c)
            out.data[size_t(i * keep + c)] =
                float((double(points.data[size_t(i * d + c)]) - f.centre[size_t(c)]) / f.scale);
        for (int64_t c = 3; c < keep; ++c) out.data[size_t(i * keep + c)] = points.data[size_t(i * d + c)];
    }
    return out;
}

std::array<double, 3> from_frame(const float* p, const ObjectFrame& f) {
    return {double(p[0]) * f.scale + f.centre[0], double(p[1]) * f.scale + f.centre[1],
            double(p[2]) * f.scale + f.centre[2]};
}

}  // namespace vtloc
