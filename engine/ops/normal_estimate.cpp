// normal_estimate: surface normals of a point cloud without any, from the k
// nearest neighbours (the point itself included) and PCA: the eigenvector of
// the neighbourhood covariance with the smallest eigenvalue, then oriented.
// -> shaders/normal_estimate.comp, one thread per point.
// Inputs: points [N, D >= 3] (xyz = columns 0..2); the grid of point_grid.h:
// order I32 [N] and cell_start I32 [G + 1]. Params: k (3..32); the grid's
// gx gy gz cell ox oy oz (set_grid_params); orient 0 (as computed), 1 (away
// from the point rx ry rz, e.g. the centroid) or 2 (towards it, e.g. a camera).
// Output: normals [N, 3], unit length; NaN rows where the neighbourhood is
// degenerate (collinear or identical points): the caller reports them.
//
// The neighbour search is exact and bit-identical on both sides (squared
// distances as sqdist3, ties broken by index, the same ring-by-ring stopping
// rule), so both pick the same neighbours; the PCA is double here and fp32 in
// the shader, so normals agree to fp32 eigenvector accuracy (see the tests).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"
#include "engine/ops/point_common.h"

namespace vtloc::ops {
namespace {

constexpr int64_t kMaxK = 32;  // the shader keeps the k best in registers

struct GridParams {
    int64_t gx, gy, gz;
    float cell, o[3];
};

GridParams grid_params(const Params& p, int64_t cells) {
    GridParams g{int_param(p, "gx", 1, 1 << 20), int_param(p, "gy", 1, 1 << 20), int_param(p, "gz", 1, 1 << 20),
                 float(p.get("cell", 0.0)), {float(p.get("ox", 0.0)), float(p.get("oy", 0.0)), float(p.get("oz", 0.0))}};
    if (!(g.cell > 0) || !std::isfinite(g.cell)) throw Error("cell must be a positive finite number");
    if (g.gx * g.gy * g.gz != cells)
        throw Error("the grid has " + std::to_string(g.gx) + "x" + std::to_string(g.gy) + "x" + std::to_string(g.gz) +
                    " cells but cell_start describes " + std::to_string(cells));
    return g;
}

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 3, 3);
    const Shape &x = in[0].shape, &order = in[1].shape, &start = in[2].shape;
    if (in[0].type != ElemType::F32 || in[1].type != ElemType::I32 || in[2].type != ElemType::I32)
        throw Error("inputs must be points F32, order I32, cell_start I32");
    if (x.size() != 2 || x[1] < 3) throw Error("points must be [N, D >= 3], got " + shape_str(x));
    const int64_t k = int_param(p, "k", 3, kMaxK);
    if (x[0] < k) throw Error("normal estimation needs at least k = " + std::to_string(k) + " points, got " +
                              std::to_string(x[0]));
    if (order != Shape{x[0]}) throw Error("order must be [N], got " + shape_str(order));
    if (start.size() != 1 || start[0] < 2) throw Error("cell_start must be [G + 1], got " + shape_str(start));
    grid_params(p, start[0] - 1);
    int_param(p, "orient", 0, 2);
    to_u32(numel(x), "point array size");
    return {TensorDesc{{x[0], 3}}};
}

// The k nearest points to point i, by (squared distance, index).
std::vector<int32_t> neighbours(const HostTensor& x, const std::vector<int32_t>& order,
                                const std::vector<int32_t>& start, const GridParams& g, int64_t i, int64_t k) {
    const int64_t D = x.shape[1];
    const float* p = &x.data[size_t(i * D)];
    const int64_t dims[3] = {g.gx, g.gy, g.gz};
    int64_t c[3];
    for (int a = 0; a < 3; ++a)
        c[a] = std::clamp<int64_t>(int64_t(std::floor((p[a] - g.o[a]) / g.cell)), 0, dims[a] - 1);
    std::vector<std::pair<float, int32_t>> best;  // sorted, at most k
    const int64_t max_r = std::max({g.gx, g.gy, g.gz});
    for (int64_t r = 0; r <= max_r; ++r) {
        for (int64_t dz = -r; dz <= r; ++dz)
            for (int64_t dy = -r; dy <= r; ++dy)
                for (int64_t dx = -r; dx <= r; ++dx) {
                    if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r) continue;
                    const int64_t cx = c[0] + dx, cy = c[1] + dy, cz = c[2] + dz;
                    if (cx < 0 || cy < 0 || cz < 0 || cx >= g.gx || cy >= g.gy || cz >= g.gz) continue;
                    const int64_t cell = (cz * g.gy + cy) * g.gx + cx;
                    for (int32_t s = start[size_t(cell)]; s < start[size_t(cell + 1)]; ++s) {
                        const int32_t j = order[size_t(s)];
                        const std::pair<float, int32_t> cand{sqdist3(p, &x.data[size_t(j * D)]), j};
                        if (int64_t(best.size()) == k && !(cand < best.back())) continue;
                        best.insert(std::upper_bound(best.begin(), best.end(), cand), cand);
                        if (int64_t(best.size()) > k) best.pop_back();
                    }
                }
        // Points of ring r + 1 lie at least r cells away; half a cell of margin keeps the
        // rule exact where the shader's division (2.5 ulp in Vulkan) picks the next cell.
        const float lim = (float(r) - 0.5f) * g.cell;
        if (int64_t(best.size()) == k && lim > 0 && best.back().first <= lim * lim) break;
    }
    std::vector<int32_t> out;
    for (const auto& b : best) out.push_back(b.second);
    return out;
}

// Unit eigenvector of the smallest eigenvalue of a symmetric 3x3 matrix (the
// trigonometric eigenvalues, then the largest cross product of two rows of
// A - lambda I); NaN if the two smallest eigenvalues are not separated.
std::array<double, 3> smallest_eigenvector(const double A[3][3]) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double p1 = A[0][1] * A[0][1] + A[0][2] * A[0][2] + A[1][2] * A[1][2];
    const double q = (A[0][0] + A[1][1] + A[2][2]) / 3.0;
    const double p2 = (A[0][0] - q) * (A[0][0] - q) + (A[1][1] - q) * (A[1][1] - q) + (A[2][2] - q) * (A[2][2] - q) + 2 * p1;
    const double p = std::sqrt(p2 / 6.0);
    if (!(p > 0)) return {nan, nan, nan};  // isotropic (or all points identical)
    // A line (or a strip over 100x longer than wide): the two smallest eigenvalues
    // vanish against the largest. Measured by the principal 2x2 minors (= ab + bc + ca),
    // not by the eigenvalues below: acos near 1 is too coarse in fp32 on some devices.
    const double tr = A[0][0] + A[1][1] + A[2][2];
    const double m2 = A[0][0] * A[1][1] - A[0][1] * A[0][1] + A[0][0] * A[2][2] - A[0][2] * A[0][2] +
                      A[1][1] * A[2][2] - A[1][2] * A[1][2];
    if (!(m2 > 1e-4 * tr * tr)) return {nan, nan, nan};
    double B[3][3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) B[r][c] = (A[r][c] - (r == c ? q : 0.0)) / p;
    const double det = B[0][0] * (B[1][1] * B[2][2] - B[1][2] * B[2][1]) - B[0][1] * (B[1][0] * B[2][2] - B[1][2] * B[2][0]) +
                       B[0][2] * (B[1][0] * B[2][1] - B[1][1] * B[2][0]);
    const double phi = std::acos(std::clamp(det / 2.0, -1.0, 1.0)) / 3.0;
    const double big = q + 2 * p * std::cos(phi);
    const double lambda = q + 2 * p * std::cos(phi + 2.0943951023931957);  // + 2 pi / 3: the smallest
    double M[3][3];
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) M[r][c] = A[r][c] - (r == c ? lambda : 0.0);
    std::array<double, 3> bestv{};
    double bestn = 0;
    for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b) {
            const std::array<double, 3> v{M[a][1] * M[b][2] - M[a][2] * M[b][1], M[a][2] * M[b][0] - M[a][0] * M[b][2],
                                          M[a][0] * M[b][1] - M[a][1] * M[b][0]};
            const double n = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            if (n > bestn) bestn = n, bestv = v;
        }
    // |cross| is the product of the other two eigenvalues' distances from lambda:
    // tiny against big^2: the smallest eigenvalue is not separated.
    if (!(std::sqrt(bestn) > 1e-6 * big * big)) return {nan, nan, nan};
    const double inv = 1.0 / std::sqrt(bestn);
    return {bestv[0] * inv, bestv[1] * inv, bestv[2] * inv};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const HostTensor& x = *in[0];
    require_finite_xyz(x, "normal_estimate");
    const std::vector<int32_t> order = in[1]->ints(), start = in[2]->ints();
    const GridParams g = grid_params(p, int64_t(start.size()) - 1);
    const int64_t N = x.shape[0], D = x.shape[1], k = int_param(p, "k", 3, kMaxK);
    const int64_t orient = int_param(p, "orient", 0, 2);
    const double ref[3] = {p.get("rx", 0.0), p.get("ry", 0.0), p.get("rz", 0.0)};
    for (int64_t i = 0; i < N; ++i) {
        const float* pi = &x.data[size_t(i * D)];
        const std::vector<int32_t> nb = neighbours(x, order, start, g, i, k);
        double m[3] = {0, 0, 0};
        for (int32_t j : nb)
            for (int a = 0; a < 3; ++a) m[a] += double(x.data[size_t(j * D + a)]) - double(pi[a]);
        for (double& v : m) v /= double(nb.size());
        double C[3][3] = {};
        for (int32_t j : nb) {
            double d[3];
            for (int a = 0; a < 3; ++a) d[a] = double(x.data[size_t(j * D + a)]) - double(pi[a]) - m[a];
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) C[r][c] += d[r] * d[c] / double(nb.size());
        }
        std::array<double, 3> n = smallest_eigenvector(C);
        if (orient != 0) {
            const double s = (orient == 1 ? 1.0 : -1.0) *
                             (n[0] * (pi[0] - ref[0]) + n[1] * (pi[1] - ref[1]) + n[2] * (pi[2] - ref[2]));
            if (s < 0) n = {-n[0], -n[1], -n[2]};
        }
        for (int a = 0; a < 3; ++a) out[0]->data[size_t(i * 3 + a)] = float(n[size_t(a)]);
    }
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t N = to_u32(a.in[0].shape[0], "points");
    const GridParams g = grid_params(a.params, a.in[2].shape[0] - 1);
    const uint32_t k = uint32_t(int_param(a.params, "k", 3, kMaxK));
    const uint32_t L = std::min(64u, elementwise_local_size(d));
    struct {
        uint32_t N, D, gx, gy, gz, orient;
        float cell, ox, oy, oz, rx, ry, rz;
    } push{N, to_u32(a.in[0].shape[1], "point width"), uint32_t(g.gx), uint32_t(g.gy), uint32_t(g.gz),
           uint32_t(int_param(a.params, "orient", 0, 2)), g.cell, g.o[0], g.o[1], g.o[2],
           float(a.params.get("rx", 0.0)), float(a.params.get("ry", 0.0)), float(a.params.get("rz", 0.0))};
    a.seq.dispatch(pipeline(a.ctx, "normal_estimate", 4, sizeof(push), {L, k}),
                   {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read},
                    {a.in[2].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), grid_groups(N, L, d));
}

}  // namespace

const OpDef op_normal_estimate{"normal_estimate", infer, cpu, gpu, 0,
                        {"k", "orient", "rx", "ry", "rz", "cell", "gx", "gy", "gz", "ox", "oy", "oz"}};

}  // namespace vtloc::ops
