#pragma once
// Double-precision 3-vectors and row-major 3x3 matrices for the tracker's host-side
// geometry (the pair search, the registration). Header-only and plain so that every
// caller rounds the same way; the GPU ops keep their own float V3 (ops/pose_evidence.h).
#include <array>
#include <cmath>

namespace vtloc::track::v3d {

using V = std::array<double, 3>;
using M = std::array<double, 9>;  // row-major

inline V sub(const V& a, const V& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline V add(const V& a, const V& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline V mul(const V& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double dot(const V& a, const V& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline V cross(const V& a, const V& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
inline double norm(const V& a) { return std::sqrt(dot(a, a)); }

inline V rotate(const M& R, const V& v) {
    return {R[0] * v[0] + R[1] * v[1] + R[2] * v[2], R[3] * v[0] + R[4] * v[1] + R[5] * v[2], R[6] * v[0] + R[7] * v[1] + R[8] * v[2]};
}

// The point v placed by the pose (R, t): t + R v, summed in compose's order (engine/rigid.h).
inline V place(const M& R, const V& t, const V& v) {
    return {t[0] + R[0] * v[0] + R[1] * v[1] + R[2] * v[2], t[1] + R[3] * v[0] + R[4] * v[1] + R[5] * v[2],
            t[2] + R[6] * v[0] + R[7] * v[1] + R[8] * v[2]};
}

inline M matmul(const M& a, const M& b) {
    M o{};
    for (size_t i = 0; i < 3; ++i)
        for (size_t j = 0; j < 3; ++j) o[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
    return o;
}

// The turn by ang about the unit axis e (Rodrigues).
inline M turn_about(const V& e, double ang) {
    const double c = std::cos(ang), s = std::sin(ang), k = 1 - c;
    return {c + k * e[0] * e[0],        k * e[0] * e[1] - s * e[2], k * e[0] * e[2] + s * e[1],
            k * e[1] * e[0] + s * e[2], c + k * e[1] * e[1],        k * e[1] * e[2] - s * e[0],
            k * e[2] * e[0] - s * e[1], k * e[2] * e[1] + s * e[0], c + k * e[2] * e[2]};
}

// A turn taking the unit vector e onto the unit vector E: the least one, except where E is
// within 2.6 degrees of -e, where the least turn's axis is ill-defined; there a half-turn
// about an axis square to e first, then the least turn from -e. Callers that care about the
// roll about E fix it themselves.
inline M align(const V& e, const V& E) {
    const double cth = dot(e, E);
    M pre{1, 0, 0, 0, 1, 0, 0, 0, 1};
    V from = e;
    if (cth < -0.999) {
        V a = cross(e, std::abs(e[0]) < 0.9 ? V{1, 0, 0} : V{0, 1, 0});
        a = mul(a, 1 / norm(a));
        for (size_t i = 0; i < 3; ++i)
            for (size_t j = 0; j < 3; ++j) pre[3 * i + j] = 2 * a[i] * a[j] - (i == j ? 1.0 : 0.0);
        from = mul(e, -1);
    }
    const V v = cross(from, E);
    const double c = dot(from, E);
    const M K{0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0};
    const M K2 = matmul(K, K);
    M R{};
    for (size_t i = 0; i < 9; ++i) R[i] = (i % 4 == 0 ? 1.0 : 0.0) + K[i] + K2[i] / (1 + c);
    return cth < -0.999 ? matmul(R, pre) : R;
}

}  // namespace vtloc::track::v3d
