#include "engine/track/registration.h"

#include "engine/track/vec3d.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace vtloc::track {

namespace {

using v3d::cross;
using v3d::dot;

// A touch as the registration sees it: its contact and gel axis in the current touch's
// frame, and its widths.
struct Contact {
    std::array<double, 3> c, z;
    double sd, sa;
};

// The turn w (Rodrigues) about the world point ctr, then the shift v: y = Rw (x - ctr) + ctr + v.
Rigid turned(const Rigid& x, const double d[6], const std::array<double, 3>& ctr) {
    Rigid m;
    m.R = rotation_of(d);
    for (size_t i = 0; i < 3; ++i)
        m.t[i] = ctr[i] + d[3 + i] - (m.R[i * 3] * ctr[0] + m.R[i * 3 + 1] * ctr[1] + m.R[i * 3 + 2] * ctr[2]);
    return compose(m, x);
}

}  // namespace

bool solve6(const double H[6][6], const double g[6], double damping, double d[6]) {
    double A[6][7];
    for (int a = 0; a < 6; ++a) {
        for (int b = 0; b < 6; ++b) A[a][b] = H[a][b] + (a == b ? damping * (1 + H[a][a]) : 0);
        A[a][6] = -g[a];
    }
    for (int c = 0; c < 6; ++c) {
        int piv = c;
        for (int r = c + 1; r < 6; ++r)
            if (std::abs(A[r][c]) > std::abs(A[piv][c])) piv = r;
        if (!(std::abs(A[piv][c]) > 1e-12)) return false;
        for (int b = 0; b < 7; ++b) std::swap(A[c][b], A[piv][b]);
        for (int r = 0; r < 6; ++r)
            if (r != c) {
                const double f = A[r][c] / A[c][c];
                for (int b = c; b < 7; ++b) A[r][b] -= f * A[c][b];
            }
    }
    for (int a = 0; a < 6; ++a) d[a] = A[a][6] / A[a][a];
    return true;
}

Rigid register_window(const NearestFacing& nearest, const std::vector<ops::pose::Term>& terms, const FilterOptions& o, Rigid x,
                      double cap) {
    std::vector<Contact> cs;
    cs.push_back({{0, 0, -o.press_mm}, {0, 0, 1}, o.sigma_d_mm, o.sigma_a_deg * M_PI / 180});
    for (const ops::pose::Term& t : terms) {
        const std::array<double, 3> z{t.rel[2], t.rel[5], t.rel[8]};
        cs.push_back({{t.trel[0] - o.press_mm * z[0], t.trel[1] - o.press_mm * z[1], t.trel[2] - o.press_mm * z[2]}, z,
                      t.sigma_d, t.sigma_a});
    }
    const double exp_floor = std::exp(o.log_floor);
    const int last = std::max(1, o.register_rounds - 1);
    std::vector<std::array<double, 3>> wc(cs.size()), wz(cs.size());
    for (int round = 0; round < o.register_rounds; ++round) {
        // register_scale halved four times over the rounds, never below the tight widths.
        const double scale = std::max(1.0, o.register_scale * std::pow(0.5, 4.0 * round / last));
        std::array<double, 3> ctr{};
        for (size_t k = 0; k < cs.size(); ++k) {
            wc[k] = v3d::place(x.R, x.t, cs[k].c), wz[k] = v3d::rotate(x.R, cs[k].z);
            for (size_t i = 0; i < 3; ++i) ctr[i] += wc[k][i] / double(cs.size());
        }
        double H[6][6] = {}, g[6] = {};
        int used = 0;
        for (size_t k = 0; k < cs.size(); ++k) {
            const float q[3] = {float(wc[k][0]), float(wc[k][1]), float(wc[k][2])};
            const float zf[3] = {float(wz[k][0]), float(wz[k][1]), float(wz[k][2])};
            const double reach = cap * cs[k].sd * scale;
            const float max_d2 = cap > 0 ? float(reach * reach) : std::numeric_limits<float>::infinity();
            const NearestFacing::Match m = nearest.query(q, zf, -0.5f, max_d2);  // a face within 60 degrees of the gel's
            if (m.index < 0) continue;
            const float* pn = m.point;
            const std::array<double, 3> p{pn[0], pn[1], pn[2]}, n{pn[3], pn[4], pn[5]}, z = wz[k];
            const std::array<double, 3> r{wc[k][0] - ctr[0], wc[k][1] - ctr[1], wc[k][2] - ctr[2]};
            const double sd = cs[k].sd * scale, sa = cs[k].sa * scale;
            // Residuals: the contact's distance along n (d/dw = r x n, d/dv = n) and the axis
            // against -n as z x n (d/dw = z n^T - (z . n) I).
            const double e_d = (wc[k][0] - p[0]) * n[0] + (wc[k][1] - p[1]) * n[1] + (wc[k][2] - p[2]) * n[2];
            const std::array<double, 3> zx = cross(z, n), rn = cross(r, n);
            const double zn = dot(z, n);
            const double qq = (e_d / sd) * (e_d / sd) + dot(zx, zx) / (sa * sa);
            const double wt = std::exp(-0.5 * qq) / (std::exp(-0.5 * qq) + exp_floor);
            if (!(wt > 1e-6)) continue;
            ++used;
            std::array<double, 7> rows[4];
            rows[0] = {rn[0] / sd, rn[1] / sd, rn[2] / sd, n[0] / sd, n[1] / sd, n[2] / sd, e_d / sd};
            for (size_t a = 0; a < 3; ++a) {
                for (size_t b = 0; b < 3; ++b) rows[1 + a][b] = (z[a] * n[b] - (a == b ? zn : 0)) / sa;
                rows[1 + a][3] = rows[1 + a][4] = rows[1 + a][5] = 0;
                rows[1 + a][6] = zx[a] / sa;
            }
            for (const auto& row : rows)
                for (size_t a = 0; a < 6; ++a) {
                    g[a] += wt * row[a] * row[6];
                    for (size_t b = 0; b < 6; ++b) H[a][b] += wt * row[a] * row[b];
                }
        }
        double d[6];
        if (used < 2 || !solve6(H, g, 1e-3, d)) break;
        // A Gauss-Newton step from far may overshoot: at most 10 degrees and 10 mm.
        const double th = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), tv = std::sqrt(d[3] * d[3] + d[4] * d[4] + d[5] * d[5]);
        const double cap = std::min({1.0, (10 * M_PI / 180) / std::max(th, 1e-12), 10 / std::max(tv, 1e-12)});
        for (double& v : d) v *= cap;
        x = turned(x, d, ctr);
    }
    return x;
}

}  // namespace vtloc::track
