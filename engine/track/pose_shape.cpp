#include "engine/track/pose_shape.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/ops/codebook_math.h"

namespace vtloc::track {

ShapeWindow shape_window(const std::vector<float>& depth_mm, int H, int W, double mm_per_px, const ScoreOptions& o) {
    check_score_options(o);
    ShapeWindow m;
    m.measured = window_map(depth_mm, H, W, mm_per_px, o.cell_mm, &m.win_mm);
    m.press = ops::book::measured_press(m.measured.data.data(), int32_t(m.measured.data.size()), o.press_percentile);
    return m;
}

// Bins of 2 mm (larger on big objects: bin_points caps them at 64 a side); a window reads
// the bins of its bounding sphere's box that its own oriented box (the window's cells and
// splat across, the cap deep) can reach: about a fifth of them.
PoseShapeScorer::PoseShapeScorer(const Surface& s, const CodebookOptions& o) : o_(o) {
    check_render_density(s, o);
    bins_ = ops::book::bin_points(s.dense, 2.0);
}

std::vector<float> PoseShapeScorer::render(const Rigid& pose, int R, int C, double win_mm) const {
    if (R < 1 || C < 1 || !(win_mm > 0)) throw Error("render-and-compare: a window of " + std::to_string(R) + " x " + std::to_string(C) + " cells");
    const double* M = pose.R.data();
    const double x[3] = {M[0], M[3], M[6]}, y[3] = {M[1], M[4], M[7]}, z[3] = {M[2], M[5], M[8]}, *t = pose.t.data();
    const double hr = (R - 1) * 0.5, hc = (C - 1) * 0.5, splat = o_.splat_mm, cap = o_.cap_mm;
    const double half_u = hc * win_mm + splat, half_v = hr * win_mm + splat;
    const double reach = std::sqrt(half_u * half_u + half_v * half_v + cap * cap);
    float lo_p[3], hi_p[3];
    for (int k = 0; k < 3; ++k) lo_p[k] = float(t[k] - reach), hi_p[k] = float(t[k] + reach);
    int64_t lo[3], hi[3];
    bins_.cell_of(lo_p, lo);
    bins_.cell_of(hi_p, hi);
    std::vector<float> depth(size_t(R) * size_t(C), float(cap));
    const double inv = 1.0 / win_mm, rc = splat * inv;
    const double co = bins_.coarse, hb = co * std::sqrt(3.0) / 2;  // a bin's centre and its points are within hb
    for (int64_t bz = lo[2]; bz <= hi[2]; ++bz)
        for (int64_t by = lo[1]; by <= hi[1]; ++by)
            for (int64_t bx = lo[0]; bx <= hi[0]; ++bx) {
                const int64_t at[3] = {bx, by, bz}, b = bins_.index_of(at);
                const int32_t first = bins_.bins[size_t(2 * b)], n = bins_.bins[size_t(2 * b + 1)];
                if (n == 0) continue;
                // Edge bins also hold the points clamped into them: test those bins by their points.
                const bool edge = bx == 0 || by == 0 || bz == 0 || bx == bins_.dims[0] - 1 || by == bins_.dims[1] - 1 || bz == bins_.dims[2] - 1;
                if (!edge) {
                    const double c[3] = {bins_.origin[0] + (bx + 0.5) * co - t[0], bins_.origin[1] + (by + 0.5) * co - t[1],
                                         bins_.origin[2] + (bz + 0.5) * co - t[2]};
                    if (std::fabs(c[0] * z[0] + c[1] * z[1] + c[2] * z[2]) > cap + hb || std::fabs(c[0] * x[0] + c[1] * x[1] + c[2] * x[2]) > half_u + hb ||
                        std::fabs(c[0] * y[0] + c[1] * y[1] + c[2] * y[2]) > half_v + hb)
                        continue;
                }
                for (int32_t k = first; k < first + n; ++k) {
                    const float* q = &bins_.points[size_t(6 * k)];
                    const double d[3] = {q[0] - t[0], q[1] - t[1], q[2] - t[2]};
                    const double h = d[0] * z[0] + d[1] * z[1] + d[2] * z[2];
                    if (std::fabs(h) > cap || q[3] * z[0] + q[4] * z[1] + q[5] * z[2] > o_.facing) continue;
                    const double fc = (d[0] * x[0] + d[1] * x[1] + d[2] * x[2]) * inv + hc;
                    const double fr = (d[0] * y[0] + d[1] * y[1] + d[2] * y[2]) * inv + hr;
                    const int c0 = std::max(0, int(std::ceil(fc - rc))), c1 = std::min(C - 1, int(std::floor(fc + rc)));
                    const int r0 = std::max(0, int(std::ceil(fr - rc))), r1 = std::min(R - 1, int(std::floor(fr + rc)));
                    for (int r = r0; r <= r1; ++r)
                        for (int c = c0; c <= c1; ++c) {
                            const double dc = c - fc, dr = r - fr;
                            if (dc * dc + dr * dr <= rc * rc) {
                                float& v = depth[size_t(r * C + c)];
                                v = std::min(v, float(h));
                            }
                        }
                }
            }
    return depth;
}

double PoseShapeScorer::score(const Rigid& pose, const ShapeWindow& m, double weight, bool quadratic, double floor) const {
    if (!(m.press > 1e-6f) || weight == 0) return 0;
    const int R = int(m.measured.shape[0]), C = int(m.measured.shape[1]);
    const std::vector<float> w = render(pose, R, C, m.win_mm);
    const double top = double(*std::min_element(w.begin(), w.end())) + m.press;
    // The error's least-squares fit on the basis (1, r, c[, r^2, c^2, r c]), taken out by
    // orthogonality as the codebook's score does (ops::book::error_basis), here in double.
    const ops::book::Basis B = ops::book::error_basis(R, C, quadratic);
    const double hr = (R - 1) * 0.5, hc = (C - 1) * 0.5;
    double s[6] = {}, s2 = 0;
    for (int r = 0; r < R; ++r)
        for (int c = 0; c < C; ++c) {
            const double a = r - hr, b = c - hc;
            const double e = m.measured.data[size_t(r * C + c)] - std::max(0.0, top - w[size_t(r * C + c)]);
            s[0] += e, s[1] += e * a, s[2] += e * b, s[3] += e * (a * a - B.mr), s[4] += e * (b * b - B.mc), s[5] += e * a * b;
            s2 += e * e;
        }
    const double inv[6] = {B.inv_n, B.inv_r, B.inv_c, B.inv_rr, B.inv_cc, B.inv_rc};
    double err = s2;
    for (int k = 0; k < 6; ++k) err -= s[k] * s[k] * inv[k];
    const double bare = -weight * std::max(0.0, err) / (double(R) * C * double(m.press) * m.press);
    if (!std::isfinite(floor)) return bare;
    return std::log(std::exp(bare) + std::exp(floor)) - std::log1p(std::exp(floor));
}

}  // namespace vtloc::track
