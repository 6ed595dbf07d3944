// SPEC section 5's uniform / non-uniform subset rule. Exact nearest
// neighbours by brute force in double precision: clouds are ~1024 points, so
// O(N^2) is a millisecond and leaves no approximation to argue about.
#include "engine/sim/uniformity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "base/error.h"

namespace vtloc::sim {

namespace {
constexpr double kDnThreshold = 30.0;
constexpr double kUniformShare = 0.7;
}  // namespace

Uniformity measure_uniformity(const HostTensor& cloud) {
    if (cloud.shape.size() != 2 || cloud.shape[1] != 6 || cloud.type != ElemType::F32)
        throw Error("measure_uniformity: cloud must be N x 6 float (xyz, normal), got " + shape_str(cloud.shape));
    const size_t n = size_t(cloud.shape[0]);
    if (n < 2) throw Error("measure_uniformity: needs at least 2 points for a nearest neighbour, got " + std::to_string(n));
    const float* d = cloud.data.data();
    for (size_t i = 0; i < 6 * n; ++i)
        if (!std::isfinite(d[i])) throw Error("measure_uniformity: point " + std::to_string(i / 6) + " is not finite");

    // Normalised frame (SPEC section 1): centre = mean, scale = max distance from it.
    double c[3] = {0, 0, 0};
    for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) c[k] += d[6 * i + k];
    for (double& v : c) v /= double(n);
    std::vector<double> p(3 * n);
    double scale = 0;
    for (size_t i = 0; i < n; ++i) {
        double r2 = 0;
        for (int k = 0; k < 3; ++k) {
            p[3 * i + k] = d[6 * i + k] - c[k];
            r2 += p[3 * i + k] * p[3 * i + k];
        }
        scale = std::max(scale, std::sqrt(r2));
    }
    if (scale > 0)
        for (double& v : p) v /= scale;

    size_t below = 0;
    for (size_t i = 0; i < n; ++i) {
        // Nearest other point; ties go to the lowest index.
        size_t best = 0;
        double best_d2 = std::numeric_limits<double>::infinity();
        for (size_t j = 0; j < n; ++j) {
            if (j == i) continue;
            double dx = p[3 * j] - p[3 * i], dy = p[3 * j + 1] - p[3 * i + 1], dz = p[3 * j + 2] - p[3 * i + 2];
            double d2 = dx * dx + dy * dy + dz * dz;
            if (d2 < best_d2) {
                best_d2 = d2;
                best = j;
            }
        }
        const float* ni = d + 6 * i + 3;
        const float* nj = d + 6 * best + 3;
        double dn2 = 0;
        for (int k = 0; k < 3; ++k) dn2 += (double(nj[k]) - ni[k]) * (double(nj[k]) - ni[k]);
        // Coincident points: dn = 0 / 0 is taken as 0 (same normal), else x / 0 = inf.
        double dn = best_d2 > 0 ? std::sqrt(dn2) / std::sqrt(best_d2)
                                : (dn2 == 0 ? 0.0 : std::numeric_limits<double>::infinity());
        if (dn < kDnThreshold) ++below;
    }
    Uniformity u;
    u.share_below = double(below) / double(n);
    u.uniform = u.share_below >= kUniformShare;
    return u;
}

}  // namespace vtloc::sim
