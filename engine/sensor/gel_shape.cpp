#include "engine/sensor/gel_shape.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "engine/sensor/gel_shading.h"

namespace vtloc::sensor {

namespace {

constexpr double kLo = -256, kHi = 256;  // colour-change range of the tables

// numpy.gradient along rows and columns: central inside, one-sided at the borders.
void gradient(const std::vector<double>& f, int H, int W, std::vector<double>& gr, std::vector<double>& gc) {
    gr.assign(f.size(), 0), gc.assign(f.size(), 0);
    auto at = [&](int r, int c) { return f[size_t(r) * W + size_t(c)]; };
    for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c) {
            gr[size_t(r) * W + size_t(c)] = r == 0 ? at(1, c) - at(0, c) : r == H - 1 ? at(r, c) - at(r - 1, c) : 0.5 * (at(r + 1, c) - at(r - 1, c));
            gc[size_t(r) * W + size_t(c)] = c == 0 ? at(r, 1) - at(r, 0) : c == W - 1 ? at(r, c) - at(r, c - 1) : 0.5 * (at(r, c + 1) - at(r, c - 1));
        }
}

int cell_of(double v, int n) { return std::clamp(int(std::floor((v - kLo) / ((kHi - kLo) / n))), 0, n - 1); }

// Empty cells (count 0) take the mean of their filled 6-neighbours, pass after pass.
void fill_empty(std::vector<double>& val, std::vector<double>& cnt, int n) {
    std::vector<uint8_t> filled(cnt.size());
    for (size_t i = 0; i < cnt.size(); ++i) filled[i] = cnt[i] > 0;
    for (bool any = true; any;) {
        any = false;
        std::vector<uint8_t> now = filled;
        for (int a = 0; a < n; ++a)
            for (int b = 0; b < n; ++b)
                for (int c = 0; c < n; ++c) {
                    const size_t i = (size_t(a) * n + size_t(b)) * n + size_t(c);
                    if (filled[i]) continue;
                    double s0 = 0, s1 = 0;
                    int k = 0;
                    const int nb[6][3] = {{a - 1, b, c}, {a + 1, b, c}, {a, b - 1, c}, {a, b + 1, c}, {a, b, c - 1}, {a, b, c + 1}};
                    for (const auto& q : nb) {
                        if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= n || q[1] >= n || q[2] >= n) continue;
                        const size_t j = (size_t(q[0]) * n + size_t(q[1])) * n + size_t(q[2]);
                        if (filled[j]) s0 += val[2 * j], s1 += val[2 * j + 1], ++k;
                    }
                    if (k) val[2 * i] = s0 / k, val[2 * i + 1] = s1 / k, now[i] = 1, any = true;
                }
        filled.swap(now);
    }
}

cv::Mat disc(int r) {
    cv::Mat k(2 * r + 1, 2 * r + 1, CV_8U, cv::Scalar(0));
    for (int y = -r; y <= r; ++y)
        for (int x = -r; x <= r; ++x) k.at<uint8_t>(y + r, x + r) = x * x + y * y <= r * r;
    return k;
}

// m (0/1) with its holes filled: background not 4-connected to the border joins it.
cv::Mat fill_holes(const cv::Mat& m) {
    cv::Mat bg;
    cv::copyMakeBorder(1 - m, bg, 1, 1, 1, 1, cv::BORDER_CONSTANT, cv::Scalar(1));
    cv::floodFill(bg, cv::Point(0, 0), cv::Scalar(2), nullptr, cv::Scalar(0), cv::Scalar(0), 4);
    return cv::Mat(bg(cv::Rect(1, 1, m.cols, m.rows)) != 2) / 255;
}

// The largest 4-connected piece of m (0/1), its holes filled.
cv::Mat largest_piece(const cv::Mat& m) {
    cv::Mat labels, stats, centroids;
    const int n = cv::connectedComponentsWithStats(m, labels, stats, centroids, 4, CV_32S);
    int best = 0, area = 0;
    for (int l = 1; l < n; ++l)
        if (stats.at<int>(l, cv::CC_STAT_AREA) > area) area = stats.at<int>(l, cv::CC_STAT_AREA), best = l;
    return fill_holes(best ? cv::Mat(cv::Mat(labels == best) / 255) : cv::Mat::zeros(m.size(), CV_8U));
}

}  // namespace

GradientLut build_gradient_lut(const Calibration& c, int n, int tiles_y, int tiles_x, int step) {
    if (n < 2 || n > 256 || tiles_y < 1 || tiles_x < 1 || step < 1) throw Error("gradient table: bad size");
    const int H = c.height, W = c.width, NB = c.bins - 1;  // the last bins are reached only at exactly 90 deg / +pi
    GradientLut lut{n, tiles_y, tiles_x, H, W, {}};
    lut.table.assign(size_t(tiles_y) * tiles_x * n * n * n * 2, 0.f);
    std::vector<float> flat;
    GelShader(c).shade(c.depth_bg, flat);
    const double dm = 0.5 * M_PI / (c.bins - 1), dd = 2 * M_PI / (c.bins - 1);
    std::vector<double> nr(size_t(NB) * NB), nc(size_t(NB) * NB);  // each bin's centre as a normal's xy
    for (int m = 0; m < NB; ++m)
        for (int d = 0; d < NB; ++d) {
            const double th = std::min((m + 0.5) * dm, M_PI / 2 - 1e-3), ph = (d + 0.5) * dd - M_PI;
            nr[size_t(m) * NB + d] = std::sin(th) * std::sin(ph), nc[size_t(m) * NB + d] = std::sin(th) * std::cos(ph);
        }
    for (int a = 0; a < tiles_y; ++a)
        for (int b = 0; b < tiles_x; ++b) {
            std::vector<double> val(size_t(n) * n * n * 2, 0), cnt(size_t(n) * n * n, 0);
            for (int y = a * H / tiles_y + step / 2; y < (a + 1) * H / tiles_y; y += step)
                for (int x = b * W / tiles_x + step / 2; x < (b + 1) * W / tiles_x; x += step) {
                    const double basis[6] = {double(x) * x, double(y) * y, double(x) * y, double(x), double(y), 1};
                    const float* f = &flat[(size_t(y) * W + size_t(x)) * 3];
                    for (int m = 0; m < NB; ++m)
                        for (int d = 0; d < NB; ++d) {
                            int q[3];
                            for (int ch = 0; ch < 3; ++ch) {
                                const float* p = &c.poly[ch][(size_t(m) * c.bins + size_t(d)) * 6];
                                double s = 0;
                                for (int k = 0; k < 6; ++k) s += double(p[k]) * basis[k];
                                q[ch] = cell_of(s - f[ch], n);
                            }
                            const size_t i = (size_t(q[0]) * n + size_t(q[1])) * n + size_t(q[2]);
                            val[2 * i] += nr[size_t(m) * NB + d], val[2 * i + 1] += nc[size_t(m) * NB + d], cnt[i] += 1;
                        }
                }
            for (size_t i = 0; i < cnt.size(); ++i)
                if (cnt[i] > 0) val[2 * i] /= cnt[i], val[2 * i + 1] /= cnt[i];
            fill_empty(val, cnt, n);
            float* out = &lut.table[(size_t(a) * tiles_x + size_t(b)) * n * n * n * 2];
            for (size_t i = 0; i < cnt.size(); ++i) {  // normals back to gradients, |n| below 1
                const double len = std::hypot(val[2 * i], val[2 * i + 1]), cap = std::min(len, 0.999);
                const double s = (len > 0 ? cap / len : 0) / std::sqrt(1 - cap * cap);
                out[2 * i] = float(val[2 * i] * s), out[2 * i + 1] = float(val[2 * i + 1] * s);
            }
        }
    return lut;
}

GelShape gel_shape(const Calibration& c, const GradientLut& lut, const std::vector<uint8_t>& frame,
                   const std::vector<uint8_t>& empty, const ShapeOptions& o) {
    const int H = c.height, W = c.width, n = lut.n, ty = lut.tiles_y, tx = lut.tiles_x;
    const size_t HW = size_t(H) * W;
    if (frame.size() != HW * 3 || empty.size() != HW * 3)
        throw Error("gel shape: frames must be " + std::to_string(W) + "x" + std::to_string(H) + " RGB, the calibration's size");
    if (lut.height != H || lut.width != W) throw Error("gel shape: the gradient table belongs to another calibration");
    // The gel's gradient: the four nearest tiles' tables, blended by the pixel's place between their centres.
    auto lookup = [&](int r, int col, const double dc3[3], double& g_row, double& g_col) {
        const size_t cell = (size_t(cell_of(dc3[0], n)) * n + size_t(cell_of(dc3[1], n))) * n + size_t(cell_of(dc3[2], n));
        const double fy = std::clamp((r + 0.5) * ty / H - 0.5, 0.0, double(ty - 1)), fx = std::clamp((col + 0.5) * tx / W - 0.5, 0.0, double(tx - 1));
        const int a0 = ty > 1 ? std::min(int(fy), ty - 2) : 0, b0 = tx > 1 ? std::min(int(fx), tx - 2) : 0;
        const double wy = fy - a0, wx = fx - b0;
        g_row = g_col = 0;
        for (int da = 0; da < 2; ++da)
            for (int db = 0; db < 2; ++db) {
                const double w = (da ? wy : 1 - wy) * (db ? wx : 1 - wx);
                const int a = std::min(a0 + da, ty - 1), b = std::min(b0 + db, tx - 1);
                const float* g = &lut.table[((size_t(a) * tx + size_t(b)) * n * n * n + cell) * 2];
                g_row += w * g[0], g_col += w * g[1];
            }
    };
    std::vector<double> gr(HW), gc(HW), zr(HW), zc(HW);
    const double none[3] = {0, 0, 0};
    for (int r = 0; r < H; ++r)
        for (int col = 0; col < W; ++col) {
            const size_t p = size_t(r) * W + size_t(col);
            const double d[3] = {double(frame[3 * p]) - empty[3 * p], double(frame[3 * p + 1]) - empty[3 * p + 1],
                                 double(frame[3 * p + 2]) - empty[3 * p + 2]};
            lookup(r, col, d, gr[p], gc[p]);
            lookup(r, col, none, zr[p], zc[p]);  // the table's answer for the untouched gel here
        }
    // The table's answer refined at the pixel itself: the (magnitude, direction) bin near it whose
    // predicted colour change is nearest the measured one (the tables average over a tile and a cell).
    std::vector<float> flat;
    if (o.refine_bins > 0) GelShader(c).shade(c.depth_bg, flat);
    const int NB = c.bins - 1;
    const double dm = 0.5 * M_PI / (c.bins - 1), dd = 2 * M_PI / (c.bins - 1);
    for (int r = 0; r < H && o.refine_bins > 0; ++r)
        for (int col = 0; col < W; ++col) {
            const size_t p = size_t(r) * W + size_t(col);
            const int m0 = std::clamp(int(std::atan(std::hypot(gr[p], gc[p])) / dm), 0, NB - 1);
            const int d0 = std::clamp(int((std::atan2(gr[p], gc[p]) + M_PI) / dd), 0, NB - 1);
            const double basis[6] = {double(col) * col, double(r) * r, double(col) * r, double(col), double(r), 1};
            double best = INFINITY;
            int bm = m0, bd = d0;
            for (int m = std::max(0, m0 - o.refine_bins); m <= std::min(NB - 1, m0 + o.refine_bins); ++m)
                for (int k = -2 * o.refine_bins; k <= 2 * o.refine_bins; ++k) {
                    const int d = ((d0 + k) % NB + NB) % NB;
                    double e = 0;
                    for (int ch = 0; ch < 3; ++ch) {
                        const float* q = &c.poly[ch][(size_t(m) * c.bins + size_t(d)) * 6];
                        double v = -double(flat[3 * p + size_t(ch)]) - (double(frame[3 * p + size_t(ch)]) - empty[3 * p + size_t(ch)]);
                        for (int j = 0; j < 6; ++j) v += double(q[j]) * basis[j];
                        e += v * v;
                    }
                    if (e < best) best = e, bm = m, bd = d;
                }
            const double th = std::min((bm + 0.5) * dm, M_PI / 2 - 1e-3), ph = (bd + 0.5) * dd - M_PI;
            gr[p] = std::tan(th) * std::sin(ph), gc[p] = std::tan(th) * std::cos(ph);
        }
    // The indentation's gradient: less the untouched gel's. Where the refinement ran, that is the
    // undeformed gel's own slope; from the tables alone, their own answer for no colour change
    // (a tile's table averages over its pixels, so it is biased where the gel's slope varies).
    std::vector<double> bg(c.depth_bg.begin(), c.depth_bg.end()), br, bc;
    gradient(bg, H, W, br, bc);
    if (o.refine_bins == 0) br.swap(zr), bc.swap(zc);
    GelShape s;
    s.height = H, s.width = W;
    cv::Mat mag(H, W, CV_64F);
    for (size_t p = 0; p < HW; ++p) {
        gr[p] -= br[p], gc[p] -= bc[p];
        mag.at<double>(int(p / W), int(p % W)) = std::hypot(gr[p], gc[p]);
    }
    s.grad_row.assign(gr.begin(), gr.end());
    s.grad_col.assign(gc.begin(), gc.end());
    // The contact: where the mean slope over 3x3 passes the threshold, opened, closed, its largest piece.
    cv::blur(mag, mag, cv::Size(3, 3), cv::Point(-1, -1), cv::BORDER_REPLICATE);
    cv::Mat m = mag > o.mask_threshold;
    m /= 255;
    // Closed and filled before the opening: a shallow press's steep ring is thinner than the
    // opening's disc, and only its filled disc survives it.
    if (o.close_radius > 0) cv::morphologyEx(m, m, cv::MORPH_CLOSE, disc(o.close_radius));
    m = fill_holes(m);
    if (o.open_radius > 0) cv::morphologyEx(m, m, cv::MORPH_OPEN, disc(o.open_radius));
    m = largest_piece(m);
    s.mask.assign(m.datastart, m.dataend);
    // Poisson: lap(z) = div(g) inside the mask, z = 0 outside (red-black SOR).
    std::vector<double> dr, unused, dc, f(HW), z(HW, 0);
    gradient(gr, H, W, dr, unused);
    gradient(gc, H, W, unused, dc);
    for (size_t p = 0; p < HW; ++p) f[p] = dr[p] + dc[p];
    for (int it = 0; it < o.sor_iterations; ++it)
        for (int colour = 0; colour < 2; ++colour)
            for (int r = 0; r < H; ++r)
                for (int col = (r + colour) % 2; col < W; col += 2) {
                    const size_t p = size_t(r) * W + size_t(col);
                    if (!s.mask[p]) continue;
                    const double nb = (r > 0 ? z[p - W] : 0) + (r + 1 < H ? z[p + W] : 0) + (col > 0 ? z[p - 1] : 0) + (col + 1 < W ? z[p + 1] : 0);
                    z[p] = (1 - o.sor_omega) * z[p] + o.sor_omega * (nb - f[p]) / 4;
                }
    s.depth_mm.resize(HW);
    for (size_t p = 0; p < HW; ++p) s.depth_mm[p] = float(s.mask[p] ? z[p] * c.mm_per_px : 0.0);
    return s;
}

Sphere fit_sphere(const std::vector<double>& xyz) {
    // x^2 + y^2 + z^2 = 2 a x + 2 b y + 2 c z + e, least squares (normal equations).
    if (xyz.size() < 12 || xyz.size() % 3) throw Error("sphere fit: needs at least 4 points");
    double A[4][4] = {}, v[4] = {};
    for (size_t i = 0; i < xyz.size(); i += 3) {
        const double row[4] = {2 * xyz[i], 2 * xyz[i + 1], 2 * xyz[i + 2], 1};
        const double rhs = xyz[i] * xyz[i] + xyz[i + 1] * xyz[i + 1] + xyz[i + 2] * xyz[i + 2];
        for (int a = 0; a < 4; ++a) {
            v[a] += row[a] * rhs;
            for (int b = 0; b < 4; ++b) A[a][b] += row[a] * row[b];
        }
    }
    for (int k = 0; k < 4; ++k) {  // Gaussian elimination with partial pivoting
        int piv = k;
        for (int r = k + 1; r < 4; ++r)
            if (std::abs(A[r][k]) > std::abs(A[piv][k])) piv = r;
        std::swap(A[k], A[piv]), std::swap(v[k], v[piv]);
        if (std::abs(A[k][k]) < 1e-12) throw Error("sphere fit: the points are degenerate (coplanar or too few)");
        for (int r = k + 1; r < 4; ++r) {
            const double f = A[r][k] / A[k][k];
            for (int b = k; b < 4; ++b) A[r][b] -= f * A[k][b];
            v[r] -= f * v[k];
        }
    }
    double s[4];
    for (int k = 3; k >= 0; --k) {
        s[k] = v[k];
        for (int b = k + 1; b < 4; ++b) s[k] -= A[k][b] * s[b];
        s[k] /= A[k][k];
    }
    Sphere out;
    out.centre = {s[0], s[1], s[2]};
    out.radius = std::sqrt(std::max(0.0, s[3] + s[0] * s[0] + s[1] * s[1] + s[2] * s[2]));
    return out;
}

}  // namespace vtloc::sensor
