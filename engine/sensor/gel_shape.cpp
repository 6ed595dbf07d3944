#include "engine/sensor/gel_shape.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "base/error.h"
#include "engine/ops/gel_mask.h"
#include "engine/parallel.h"
#include "engine/ops/gel_ops.h"
#include "engine/sensor/gel_linear_inverse.h"
#include "engine/sensor/gel_shading.h"

namespace vtloc::sensor {

namespace {

// Empty cells (count 0) take the mean of their filled 6-neighbours, pass after pass; a pass reads
// only the cells filled before it. Each pass visits only its front (the empty cells next to a
// filled one), not every cell: the same means in the same order, a fraction of the work (the
// whole grid once a pass was most of building the table).
void fill_empty(std::vector<double>& val, const std::vector<double>& cnt, int n) {
    const size_t N = cnt.size();
    std::vector<uint8_t> filled(N), queued(N);
    for (size_t i = 0; i < N; ++i) filled[i] = cnt[i] > 0;
    // fn(j) for each neighbour j of cell i inside the grid, in the order -a, +a, -b, +b, -c, +c.
    auto each_neighbour = [n](size_t i, auto&& fn) {
        const size_t nn = size_t(n), c = i % nn, b = i / nn % nn, a = i / (nn * nn);
        if (a > 0) fn(i - nn * nn);
        if (a + 1 < nn) fn(i + nn * nn);
        if (b > 0) fn(i - nn);
        if (b + 1 < nn) fn(i + nn);
        if (c > 0) fn(i - 1);
        if (c + 1 < nn) fn(i + 1);
    };
    std::vector<size_t> front, next;
    for (size_t i = 0; i < N; ++i) {
        if (filled[i]) continue;
        bool touches = false;
        each_neighbour(i, [&](size_t j) { touches = touches || filled[j]; });
        if (touches) front.push_back(i), queued[i] = 1;
    }
    std::vector<double> mean;
    while (!front.empty()) {
        mean.assign(2 * front.size(), 0.0);
        for (size_t f = 0; f < front.size(); ++f) {
            double s0 = 0, s1 = 0;
            int k = 0;
            each_neighbour(front[f], [&](size_t j) {
                if (filled[j]) s0 += val[2 * j], s1 += val[2 * j + 1], ++k;
            });
            mean[2 * f] = s0 / k, mean[2 * f + 1] = s1 / k;  // k >= 1: the front touches a filled cell
        }
        for (size_t f = 0; f < front.size(); ++f)
            val[2 * front[f]] = mean[2 * f], val[2 * front[f] + 1] = mean[2 * f + 1], filled[front[f]] = 1;
        next.clear();
        for (size_t i : front)
            each_neighbour(i, [&](size_t j) {
                if (!filled[j] && !queued[j]) queued[j] = 1, next.push_back(j);
            });
        front.swap(next);
    }
}

}  // namespace

GradientLut build_gradient_lut(const Calibration& c, int threads, const LutGrid& grid) {
    const int n = grid.n, tiles_y = grid.tiles_y, tiles_x = grid.tiles_x, step = grid.step;
    if (n < 2 || n > 256 || tiles_y < 1 || tiles_x < 1 || step < 1) throw Error("gradient table: bad size");
    if (threads < 0) throw Error("gradient table: threads must be >= 0 (0: up to 4)");
    const int H = c.height, W = c.width, NB = c.bins - 1;  // the last bins are reached only at exactly 90 deg / +pi
    GradientLut lut{n, tiles_y, tiles_x, H, W, {}, build_linear_inverse(c, kLinearMaxSlope, threads)};
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
    // The polynomials' coefficients as doubles, [channel][k][bin] over the NB x NB bins, so that
    // a pixel's 3 x 6 multiply-adds per bin run as vectors across bins: the same products summed
    // in the same order as one bin at a time, so the same table bit for bit (docs/gel_shape.md,
    // "Building the tables").
    const size_t nbin = size_t(NB) * size_t(NB);
    std::vector<double> coef(3 * 6 * nbin);
    for (int ch = 0; ch < 3; ++ch)
        for (int m = 0; m < NB; ++m)
            for (int d = 0; d < NB; ++d)
                for (int k = 0; k < 6; ++k)
                    coef[(size_t(ch) * 6 + size_t(k)) * nbin + size_t(m) * NB + size_t(d)] =
                        double(c.poly[ch][(size_t(m) * c.bins + size_t(d)) * 6 + size_t(k)]);
    // The tiles on the host's threads: each fills its own part of the table from its own sums,
    // so the table is the same bits on any number of threads.
    parallel_for(size_t(tiles_y) * size_t(tiles_x), threads, [&](size_t tile) {
        const int a = int(tile / size_t(tiles_x)), b = int(tile % size_t(tiles_x));
        std::vector<double> sum(nbin);
        std::vector<uint32_t> cell(nbin);  // n <= 256: n^3 fits
        std::vector<double> val(size_t(n) * n * n * 2, 0), cnt(size_t(n) * n * n, 0);
        for (int y = a * H / tiles_y + step / 2; y < (a + 1) * H / tiles_y; y += step)
            for (int x = b * W / tiles_x + step / 2; x < (b + 1) * W / tiles_x; x += step) {
                const double basis[6] = {double(x) * x, double(y) * y, double(x) * y, double(x), double(y), 1};
                const float* f = &flat[(size_t(y) * W + size_t(x)) * 3];
                for (int ch = 0; ch < 3; ++ch) {
                    const double* p = &coef[size_t(ch) * 6 * nbin];
                    for (size_t i = 0; i < nbin; ++i) {
                        double s = 0;
                        for (int k = 0; k < 6; ++k) s += p[size_t(k) * nbin + i] * basis[k];
                        sum[i] = s;
                    }
                    const float fc = f[ch];
                    for (size_t i = 0; i < nbin; ++i) {  // the cell the lookup reads
                        const uint32_t q = uint32_t(ops::gel::cell_of(float(sum[i] - fc), n));
                        cell[i] = ch == 0 ? q : cell[i] * uint32_t(n) + q;
                    }
                }
                for (size_t i = 0; i < nbin; ++i) {  // bins in the order (m, d), as before
                    val[2 * size_t(cell[i])] += nr[i], val[2 * size_t(cell[i]) + 1] += nc[i], cnt[cell[i]] += 1;
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
    });
    return lut;
}

std::vector<uint8_t> contact_mask(const std::vector<float>& grad, int H, int W, const ShapeOptions& o) {
    if (grad.size() != size_t(H) * size_t(W) * 2) throw Error("contact mask: the gradient must be H x W x 2");
    return ops::gel::contact_mask(grad.data(), H, W, float(o.mask_threshold), o.close_radius, o.open_radius);
}

GelShape gel_shape(const Calibration& c, const GradientLut& lut, const std::vector<uint8_t>& frame,
                   const std::vector<uint8_t>& empty, const ShapeOptions& o) {
    const int H = c.height, W = c.width;
    const size_t HW = size_t(H) * W;
    if (frame.size() != HW * 3 || empty.size() != HW * 3)
        throw Error("gel shape: frames must be " + std::to_string(W) + "x" + std::to_string(H) + " RGB, the calibration's size");
    if (lut.height != H || lut.width != W || lut.linear.size() != HW * 6)
        throw Error("gel shape: the gradient table belongs to another calibration");
    // The indentation's gradient, as op gel_gradient computes it.
    const std::vector<float> f(frame.begin(), frame.end()), e(empty.begin(), empty.end());
    std::vector<float> grad(HW * 2);
    for (int r = 0; r < H; ++r)
        for (int col = 0; col < W; ++col) {
            float* g = &grad[(size_t(r) * W + size_t(col)) * 2];
            ops::gel::indentation_gradient(lut.table.data(), lut.n, lut.tiles_y, lut.tiles_x, H, W, f.data(), e.data(), lut.linear.data(),
                                           float(o.gentle_slope), r, col, g[0], g[1]);
        }
    GelShape s;
    s.height = H, s.width = W;
    s.grad_row.resize(HW), s.grad_col.resize(HW);
    for (size_t p = 0; p < HW; ++p) s.grad_row[p] = grad[2 * p], s.grad_col[p] = grad[2 * p + 1];
    s.mask = contact_mask(grad, H, W, o);
    // The height inside the mask, as op masked_poisson computes it.
    std::vector<float> mask(s.mask.begin(), s.mask.end()), z(HW);
    ops::gel::masked_poisson_multilevel(grad.data(), mask.data(), H, W, o.sor_levels, o.sor_iterations, o.sor_coarse_iterations,
                                        float(o.sor_omega), z.data());
    s.depth_mm.resize(HW);
    for (size_t p = 0; p < HW; ++p) s.depth_mm[p] = s.mask[p] ? float(double(z[p]) * c.mm_per_px) : 0.0f;
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
