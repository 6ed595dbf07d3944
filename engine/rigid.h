#pragma once
// A rigid motion or pose (SPEC 6's conventions) and its checks, header-only so
// that the file readers (engine/io) and the tracker (engine/track) share them
// without a link dependency.
#include <array>
#include <cmath>
#include <string>

#include "base/error.h"

namespace vtloc {

// R row-major, then t. As a motion from touch a to b: pose b in pose a's frame
// (Q = R_a^T R_b, q = R_a^T (t_b - t_a)).
struct Rigid {
    std::array<double, 9> R{1, 0, 0, 0, 1, 0, 0, 0, 1};
    std::array<double, 3> t{};
};

// a then b in a's frame: (Ra Rb, ta + Ra tb).
inline Rigid compose(const Rigid& a, const Rigid& b) {
    Rigid o;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c)
            o.R[size_t(r * 3 + c)] = a.R[size_t(r * 3)] * b.R[size_t(c)] + a.R[size_t(r * 3 + 1)] * b.R[size_t(3 + c)] +
                                     a.R[size_t(r * 3 + 2)] * b.R[size_t(6 + c)];
        o.t[size_t(r)] = a.t[size_t(r)] + a.R[size_t(r * 3)] * b.t[0] + a.R[size_t(r * 3 + 1)] * b.t[1] +
                         a.R[size_t(r * 3 + 2)] * b.t[2];
    }
    return o;
}

inline Rigid inverse(const Rigid& a) {
    Rigid o;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) o.R[size_t(r * 3 + c)] = a.R[size_t(c * 3 + r)];
    for (int r = 0; r < 3; ++r)
        o.t[size_t(r)] = -(o.R[size_t(r * 3)] * a.t[0] + o.R[size_t(r * 3 + 1)] * a.t[1] + o.R[size_t(r * 3 + 2)] * a.t[2]);
    return o;
}

// Throws naming `what` unless R is a rotation (orthonormal within 1e-4, det +1) and all finite.
inline void check_rigid(const Rigid& m, const std::string& what) {
    for (double v : m.R)
        if (!std::isfinite(v)) throw Error(what + ": the rotation holds NaN or inf");
    for (double v : m.t)
        if (!std::isfinite(v)) throw Error(what + ": the translation holds NaN or inf");
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            double d = 0;
            for (int k = 0; k < 3; ++k) d += m.R[size_t(k * 3 + a)] * m.R[size_t(k * 3 + b)];
            if (std::abs(d - (a == b ? 1.0 : 0.0)) > 1e-4)
                throw Error(what + ": the 3x3 part is not a rotation (its columns are not orthonormal)");
        }
    const auto& R = m.R;
    const double det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) + R[2] * (R[3] * R[7] - R[4] * R[6]);
    if (det < 0) throw Error(what + ": the 3x3 part is a reflection (determinant -1), not a rotation");
}

// A 4x4 matrix given row by row as a checked rigid transform: its last row must be
// 0 0 0 1 and its 3x3 part a rotation (check_rigid). Throws naming `what`.
inline Rigid rigid_from_rows(const std::array<double, 16>& v, const std::string& what) {
    for (size_t i = 0; i < 16; ++i)  // first, so that a NaN in the last row is named as one
        if (!std::isfinite(v[i]))
            throw Error(what + ": row " + std::to_string(i / 4) + ", column " + std::to_string(i % 4) + " holds NaN or inf");
    if (v[12] != 0 || v[13] != 0 || v[14] != 0 || v[15] != 1) throw Error(what + ": the last row must be 0 0 0 1");
    Rigid out;
    for (size_t r = 0; r < 3; ++r) {
        for (size_t c = 0; c < 3; ++c) out.R[r * 3 + c] = v[4 * r + c];
        out.t[r] = v[4 * r + 3];
    }
    check_rigid(out, what);
    return out;
}

// The rotation by the angle |w| about the axis w (Rodrigues), row-major; the identity for w = 0.
inline std::array<double, 9> rotation_of(const double w[3]) {
    const double th = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (!(th > 0)) return {1, 0, 0, 0, 1, 0, 0, 0, 1};
    const double k[3] = {w[0] / th, w[1] / th, w[2] / th}, c = std::cos(th), s = std::sin(th), v = 1 - c;
    return {c + k[0] * k[0] * v,        k[0] * k[1] * v - k[2] * s, k[0] * k[2] * v + k[1] * s,
            k[1] * k[0] * v + k[2] * s, c + k[1] * k[1] * v,        k[1] * k[2] * v - k[0] * s,
            k[2] * k[0] * v - k[1] * s, k[2] * k[1] * v + k[0] * s, c + k[2] * k[2] * v};
}

// The sensor's motion between two flange poses (robot frame) with the flange-to-sensor
// tool: sensor_k = flange_k tool, motion = sensor_a^-1 sensor_b.
inline Rigid sensor_motion(const Rigid& flange_a, const Rigid& flange_b, const Rigid& tool) {
    return compose(inverse(compose(flange_a, tool)), compose(flange_b, tool));
}

}  // namespace vtloc
