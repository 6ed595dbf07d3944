#pragma once
// Helpers shared by the point-cloud ops (fps, ball_query, point_group, group_linear).
#include <cmath>
#include <cstdint>
#include <string>

#include "base/error.h"
#include "engine/graph.h"
#include "engine/tensor.h"

namespace vtloc::ops {

// The reference's squared distance: (dx*dx + dy*dy) + dz*dz in float, one
// rounding per operation. Each product is its own statement and the build has
// no -march/-mfma, so the compiler cannot contract it into an fma.
inline float sqdist3(const float* a, const float* c) {
    float dx = a[0] - c[0], dy = a[1] - c[1], dz = a[2] - c[2];
    float xx = dx * dx, yy = dy * dy, zz = dz * dz;
    float xy = xx + yy;
    return xy + zz;
}

// W [out, in(, 1, 1)] -> W^T [in, out], the layout group_linear reads (group_linear.cpp).
HostTensor point_weight_kn(const HostTensor& w);

// An integer parameter in [lo, hi]; throws naming it otherwise.
inline int64_t int_param(const Params& p, const char* name, int64_t lo, int64_t hi) {
    const double v = p.get(name, double(lo) - 1.0);
    if (!(v >= double(lo) && v <= double(hi)) || v != std::floor(v))
        throw Error(std::string(name) + " must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi) +
                    ", got " + (p.has(name) ? std::to_string(v) : std::string("none")));
    return int64_t(v);
}

// int_param that must also be a power of two (workgroup sizes, lanes per group).
inline int64_t pow2_param(const Params& p, const char* name, int64_t lo, int64_t hi) {
    const int64_t v = int_param(p, name, lo, hi);
    if (v & (v - 1)) throw Error(std::string(name) + " = " + std::to_string(v) + " must be a power of two");
    return v;
}

// CPU references throw on NaN/inf coordinates (the GPU path relies on the host
// check before upload: object_frame / check_object_cloud).
inline void require_finite_xyz(const HostTensor& x, const char* op) {
    const int64_t D = x.shape.back(), N = x.size() / D;
    for (int64_t i = 0; i < N; ++i)
        for (int64_t k = 0; k < 3; ++k)
            if (!std::isfinite(x.data[size_t(i * D + k)]))
                throw Error(std::string(op) + ": point " + std::to_string(i) + " has a NaN or infinite coordinate");
}

// Grouping (point_group, and group_linear's gather): inputs points [P, D >= 3],
// centres [S, 3], idx I32 [S, NS] and optionally features [P, DF] of which
// columns FB.. are used (param feat_begin; CF = DF - FB, 0 without features).
// Row m = s * NS + j of the grouped matrix is [features of q, xyz of q - centre s],
// q = idx[s, j]: K = CF + 3 columns.
struct GatherShape {
    int64_t P = 0, D = 0, S = 0, NS = 0, DF = 0, FB = 0, CF = 0;
    int64_t rows() const { return S * NS; }
    int64_t K() const { return CF + 3; }
};

inline GatherShape gather_shape(const TensorDesc& points, const TensorDesc& centres, const TensorDesc& idx,
                                const TensorDesc* feat, const Params& p) {
    GatherShape g;
    if (points.type != ElemType::F32 || centres.type != ElemType::F32 || (feat && feat->type != ElemType::F32))
        throw Error("points, centres and features must be F32");
    if (idx.type != ElemType::I32) throw Error("ball indices must be I32");
    if (points.shape.size() != 2 || points.shape[1] < 3)
        throw Error("points must be [P, D >= 3], got " + shape_str(points.shape));
    if (centres.shape.size() != 2 || centres.shape[1] != 3)
        throw Error("centres must be [S, 3], got " + shape_str(centres.shape));
    if (idx.shape.size() != 2 || idx.shape[0] != centres.shape[0])
        throw Error("ball indices " + shape_str(idx.shape) + " must be [S, nsample] for centres " +
                    shape_str(centres.shape));
    g.P = points.shape[0], g.D = points.shape[1], g.S = centres.shape[0], g.NS = idx.shape[1];
    if (g.P == 0) throw Error("the point cloud is empty");
    if (g.NS == 0) throw Error("nsample must be at least 1");
    if (feat) {
        if (feat->shape.size() != 2 || feat->shape[0] != g.P)
            throw Error("features " + shape_str(feat->shape) + " must have one row per point (" + std::to_string(g.P) + ")");
        g.DF = feat->shape[1];
        g.FB = p.has("feat_begin") ? int_param(p, "feat_begin", 0, g.DF) : 0;
        g.CF = g.DF - g.FB;
    }
    return g;
}

// Row m of a ball [S, NS] is padding (SPEC 2: a free slot repeats the ball's first
// index): raw indices, as point_mlp.glsl compares them (group_linear's param pad).
inline bool padding_row(const HostTensor& idx, int64_t m, int64_t NS) {
    const int64_t m0 = m / NS * NS;
    return m != m0 && idx.int_at(size_t(m)) == idx.int_at(size_t(m0));
}

// Element (m, k) of the grouped matrix; the offset in float, as the shader computes it.
// CPU references: the source point of ball row m, refused when outside the P points.
inline int32_t ball_point(const HostTensor& idx, int64_t m, int64_t P) {
    const int32_t q = idx.int_at(size_t(m));
    if (q < 0 || q >= P) throw Error("ball index " + std::to_string(q) + " is outside the " + std::to_string(P) + " points");
    return q;
}

// CPU references: a centre's share of output channel n of a layer whose input-major
// weight w [K, N] has its xyz rows from row `xyz_row` (what sa_gather subtracts).
inline double centre_share(const HostTensor& w, int64_t xyz_row, int64_t N, int64_t n, const float* centre) {
    double s = 0;
    for (int k = 0; k < 3; ++k) s += double(w.data[size_t((xyz_row + k) * N + n)]) * centre[k];
    return s;
}

inline float gather_value(const HostTensor& pts, const HostTensor& centres, const HostTensor& idx,
                          const HostTensor* feat, const GatherShape& g, int64_t m, int64_t k) {
    const int32_t q = ball_point(idx, m, g.P);
    if (k < g.CF) return feat->data[size_t(q * g.DF + g.FB + k)];
    const int64_t c = k - g.CF;
    return pts.data[size_t(q * g.D + c)] - centres.data[size_t(3 * (m / g.NS) + c)];
}

}  // namespace vtloc::ops
