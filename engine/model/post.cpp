#include "engine/model/post.h"

#include <algorithm>
#include <limits>

#include <cmath>
#include <numbers>

#include "base/error.h"

namespace vtloc {

HostTensor symmetry_transforms(const std::array<double, 3>& axis_point, const std::array<double, 3>& axis_dir,
                               int order) {
    if (order < 1) throw Error("symmetry order must be >= 1, got " + std::to_string(order));
    double len = std::sqrt(axis_dir[0] * axis_dir[0] + axis_dir[1] * axis_dir[1] + axis_dir[2] * axis_dir[2]);
    if (!(len > 0) || !std::isfinite(len)) throw Error("symmetry axis direction must be finite and non-zero");
    for (double v : axis_point)
        if (!std::isfinite(v)) throw Error("symmetry axis point must be finite");
    const double k[3] = {axis_dir[0] / len, axis_dir[1] / len, axis_dir[2] / len};
    HostTensor out({order, 12});
    for (int m = 0; m < order; ++m) {
        const double angle = 2 * std::numbers::pi * m / order, c = std::cos(angle), s = std::sin(angle);
        // Rodrigues: R = c I + s [k]x + (1 - c) k k^T
        const double R[3][3] = {
            {c + (1 - c) * k[0] * k[0], (1 - c) * k[0] * k[1] - s * k[2], (1 - c) * k[0] * k[2] + s * k[1]},
            {(1 - c) * k[1] * k[0] + s * k[2], c + (1 - c) * k[1] * k[1], (1 - c) * k[1] * k[2] - s * k[0]},
            {(1 - c) * k[2] * k[0] - s * k[1], (1 - c) * k[2] * k[1] + s * k[0], c + (1 - c) * k[2] * k[2]}};
        for (int r = 0; r < 3; ++r) {
            double t = axis_point[size_t(r)];
            for (int j = 0; j < 3; ++j) {
                out.data[size_t(12 * m + 4 * r + j)] = float(R[r][j]);
                t -= R[r][j] * axis_point[size_t(j)];
            }
            out.data[size_t(12 * m + 4 * r + 3)] = float(t);
        }
    }
    return out;
}

void require_finite(const HostTensor& t, const std::string& what) {
    if (t.type != ElemType::F32) return;
    for (size_t i = 0; i < t.data.size(); ++i)
        if (!std::isfinite(t.data[i]))
            throw Error(what + " holds " + (std::isnan(t.data[i]) ? "NaN" : "inf") + " at element " + std::to_string(i));
}

}  // namespace vtloc
