#pragma once
// The sensor pose the tracker tests put on a surface point: pressing `press` mm along the
// inward normal, spun by `spin` about its axis from the renderer's tangent (track::tangent_of).
#include <array>
#include <cmath>

#include "engine/track/surface.h"
#include "engine/track/tracker.h"

namespace vtloc::test {

// p: a point and its outward normal (6 floats).
inline track::Rigid pose_at(const float* p, double spin, double press) {
    const std::array<double, 3> z{-p[3], -p[4], -p[5]};
    const std::array<double, 3> t1 = track::tangent_of(z);
    const std::array<double, 3> t2{z[1] * t1[2] - z[2] * t1[1], z[2] * t1[0] - z[0] * t1[2], z[0] * t1[1] - z[1] * t1[0]};
    std::array<double, 3> x, y;
    for (int k = 0; k < 3; ++k) x[size_t(k)] = std::cos(spin) * t1[size_t(k)] + std::sin(spin) * t2[size_t(k)];
    y = {z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]};
    track::Rigid r;
    r.R = {x[0], y[0], z[0], x[1], y[1], z[1], x[2], y[2], z[2]};
    for (int k = 0; k < 3; ++k) r.t[size_t(k)] = p[k] + press * z[size_t(k)];
    return r;
}

}  // namespace vtloc::test
