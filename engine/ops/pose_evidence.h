#pragma once
// The per-pose arithmetic of the multi-touch filter (SPEC 6), shared by
// pose_evidence's CPU reference and the tracker's continuous refinement, and
// mirrored line for line by shaders/pose_evidence.comp. fp32 in the same order
// as the shader, which marks the lookups `precise`: a pose lands in the same
// grid cell, face and spin on both, so only exp/log/atan/sqrt differ (within tolerance).
#include <cmath>
#include <cstdint>
#include <vector>

namespace vtloc::ops::pose {

struct V3 {
    float x, y, z;
};
inline V3 add(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 sub(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 mul(V3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline float dot(V3 a, V3 b) { return (a.x * b.x + a.y * b.y) + a.z * b.z; }
inline V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline V3 load3(const float* p) { return {p[0], p[1], p[2]}; }

// A sensor pose: axes x (image columns), y (rows), z (into the object), centre t.
struct Frame {
    V3 x, y, z, t;
};

// The lookup grid over the object (engine/track/surface.h builds it): per cell, the
// nearest dense surface point and its nearest counterpart whose normal turns the other
// way (a thin part's far face; -1: none within the grid's band); per dense point, the
// hypothesis sample a pose pressing it reads a field at (-1: none near).
struct Grid {
    const float* dense;           // [D, 6] point, outward unit normal
    const int32_t* dense_sample;  // [D]
    const int32_t* cells;         // [nx * ny * nz, 2]
    const float* samples;         // [S, 9] point, normal, tangent t1
    const float* spins;           // [NS, 2] cos, sin
    int32_t n_spin;
    V3 origin;
    float voxel;
    int32_t nx, ny, nz;
};

// One touch of the window seen from the hypothesis' touch: its pose is
// R_k = R rel, t_k = t + R trel; geometry scored where sigma_d > 0; a field
// (a log term over the hypotheses) read at the pose where field >= 0.
struct Term {
    float rel[9];  // row-major
    float trel[3];
    float sigma_d, sigma_a;
    int32_t field;
    float weight;
};
inline Term term_from_row(const float* r) {
    Term t;
    for (int i = 0; i < 9; ++i) t.rel[i] = r[i];
    for (int i = 0; i < 3; ++i) t.trel[i] = r[9 + i];
    t.sigma_d = r[12];
    t.sigma_a = r[13];
    t.field = int32_t(std::lround(r[14]));
    t.weight = r[15];
    return t;
}

// Hypothesis h = sample * NS + spin: z = -n, x = cos t1 + sin t2 with t2 = z x t1
// (the renderer's tangent basis), y = z x x, t = p + press z.
inline Frame hypothesis_frame(const Grid& g, int64_t h, float press) {
    const int64_t s = h / g.n_spin, j = h % g.n_spin;
    const float* smp = g.samples + s * 9;
    V3 z = mul(load3(smp + 3), -1.0f), t1 = load3(smp + 6);
    V3 t2 = cross(z, t1);
    V3 x = add(mul(t1, g.spins[j * 2]), mul(t2, g.spins[j * 2 + 1]));
    return {x, cross(z, x), z, add(load3(smp), mul(z, press))};
}

inline Frame moved(const Frame& f, const Term& k) {
    const float* r = k.rel;
    Frame o;
    o.x = add(add(mul(f.x, r[0]), mul(f.y, r[3])), mul(f.z, r[6]));
    o.y = add(add(mul(f.x, r[1]), mul(f.y, r[4])), mul(f.z, r[7]));
    o.z = add(add(mul(f.x, r[2]), mul(f.y, r[5])), mul(f.z, r[8]));
    o.t = add(add(add(f.t, mul(f.x, k.trel[0])), mul(f.y, k.trel[1])), mul(f.z, k.trel[2]));
    return o;
}

// std::floor, without the library call baseline x86-64 (no SSE4.1) makes of it: below
// 2^22 in size a float converts to an integer exactly (truncating toward zero), one step
// down where that rounded a negative up, v itself where it was whole (-0 keeps its sign);
// larger, infinite or NaN: std::floor itself.
inline float floor_of(float v) {
    if (!(v > -4194304.0f && v < 4194304.0f)) return std::floor(v);
    const float t = float(int32_t(v));
    return t > v ? t - 1.0f : t < v ? t : v;
}

// The grid cell holding point q, or -1 outside the grid.
inline int64_t cell_of(const Grid& g, V3 q) {
    V3 u = mul(sub(q, g.origin), 1.0f / g.voxel);
    float fx = floor_of(u.x), fy = floor_of(u.y), fz = floor_of(u.z);
    if (!(fx >= 0 && fy >= 0 && fz >= 0 && fx < float(g.nx) && fy < float(g.ny) && fz < float(g.nz))) return -1;
    return (int64_t(fz) * g.ny + int64_t(fy)) * g.nx + int64_t(fx);
}

// The dense point a pose with axis z presses in a cell: the cell's nearest point or,
// where z runs along that point's outward normal (the gel then presses the other
// face), its far-face counterpart if it has one; -1: none near.
inline int32_t pressed_point(const Grid& g, int64_t cell, V3 z) {
    if (cell < 0) return -1;
    const int32_t* c = g.cells + cell * 2;
    if (c[0] < 0) return -1;
    return c[1] >= 0 && dot(z, load3(g.dense + int64_t(c[0]) * 6 + 3)) > 0.0f ? c[1] : c[0];
}

// The hypothesis nearest a pose (axes x, z): the sample of the dense point it presses
// and the spin whose x axis is closest to the pose's (lowest spin on a tie); -1 when
// no sample is near.
inline int64_t nearest_hypothesis(const Grid& g, int64_t cell, V3 x, V3 z) {
    const int32_t i = pressed_point(g, cell, z);
    const int32_t s = i < 0 ? -1 : g.dense_sample[i];
    if (s < 0) return -1;
    const float* smp = g.samples + int64_t(s) * 9;
    V3 t1 = load3(smp + 6), t2 = cross(mul(load3(smp + 3), -1.0f), t1);
    float a = dot(x, t1), b = dot(x, t2);
    int32_t best = 0;
    float best_v = -3.0f;
    for (int32_t j = 0; j < g.n_spin; ++j) {
        float v = g.spins[j * 2] * a + g.spins[j * 2 + 1] * b;
        if (v > best_v) best_v = v, best = j;
    }
    return int64_t(s) * g.n_spin + best;
}

// The robust Gaussian of a squared, width-scaled error q: log(exp(-q / 2) + exp_floor).
inline float robust_log(float q, float exp_floor) { return std::log(std::exp(-0.5f * q) + exp_floor); }

// Geometry: the pose's gel centre should sit `press` inside the surface and its
// axis along the inward normal; a robust Gaussian (floor exp_floor = exp(log_floor), from
// the caller: one exp a term less, as the shader's push constant).
// The distance is to the tangent plane of the dense point the pose presses.
inline float geometry_log(const Grid& g, int64_t cell, const Frame& f, float press, float sigma_d, float sigma_a,
                          float log_floor, float exp_floor) {
    const int32_t i = pressed_point(g, cell, f.z);
    if (i < 0) return log_floor;
    V3 p = load3(g.dense + int64_t(i) * 6), n = load3(g.dense + int64_t(i) * 6 + 3);
    float e_d = dot(sub(f.t, p), n) + press;
    // The axis' angle to the inward normal as atan2(|z x n|, -z.n): lavapipe's acos is a
    // polynomial (errors of order 1e-4 to 1e-3 rad) that a narrow sigma_a magnifies.
    V3 w = cross(f.z, n);
    float e_a = std::atan2(std::sqrt(dot(w, w)), -dot(f.z, n));
    float q = (e_d / sigma_d) * (e_d / sigma_d) + (e_a / sigma_a) * (e_a / sigma_a);
    return robust_log(q, exp_floor);
}

// pose_evidence's input rows, padded to vec4s (on a CPU driver every read at a varying
// offset is a loop over the lanes, whatever its width): samples [S, 9] -> [S, 12]
// (point, 0, normal, 0, t1, 0); dense [D, 6] and each point's sample -> [D, 8] (point,
// sample as a float, normal, 0).
// Float k (0..8) of a sample's [9] row sits at this offset of its [12] row.
inline size_t padded_sample_offset(size_t k) { return k / 3 * 4 + k % 3; }
inline std::vector<float> evidence_samples(const std::vector<float>& s9) {
    std::vector<float> r(s9.size() / 9 * 12, 0.0f);
    for (size_t i = 0; i < s9.size() / 9; ++i)
        for (size_t k = 0; k < 9; ++k) r[12 * i + padded_sample_offset(k)] = s9[9 * i + k];
    return r;
}
inline std::vector<float> evidence_dense(const std::vector<float>& d6, const std::vector<int32_t>& sample) {
    std::vector<float> r(d6.size() / 6 * 8, 0.0f);
    for (size_t i = 0; i < d6.size() / 6; ++i) {
        for (size_t k = 0; k < 3; ++k) r[8 * i + k] = d6[6 * i + k], r[8 * i + 4 + k] = d6[6 * i + 3 + k];
        r[8 * i + 3] = float(sample[i]);
    }
    return r;
}

}  // namespace vtloc::ops::pose
