#pragma once
// Render-and-compare's arithmetic (SPEC 9; docs/render_compare.md), shared by the
// CPU references of codebook_render and codebook_score and mirrored line for
// line by shaders/codebook_render.comp and shaders/codebook_score.comp: fp32 in
// the shaders' order (they mark it `precise`), so a point lands in the same
// cell on both and a height map compares bit for bit.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "engine/ops/pose_evidence.h"

namespace vtloc::ops::book {

using pose::V3;

// A height map per surface sample: G x G cells of `cell` mm in the sample's
// tangent plane (along t1, then t2 = z x t1; cell (i, j) at ((i - (G-1)/2) cell,
// (j - (G-1)/2) cell)), each the smallest depth along the axis z = -n from the
// sample's point of a dense point facing the sensor whose splat disc covers the
// cell's centre; depths beyond +-cap are dropped and an empty cell holds cap
// (no surface near enough to touch the gel).
struct RenderParams {
    int32_t G;
    float cell, splat, cap, facing;  // facing: largest n_q . z kept (back faces face away)
    V3 origin;                       // the dense points' binning grid (cells of `coarse` mm)
    float coarse;
    float inv_cell, inv_coarse;      // float(1 / cell), float(1 / coarse): shaders may not divide exactly
    int32_t nx, ny, nz;
};

// Order-preserving float <-> uint, so an unsigned atomic minimum is a float one.
inline uint32_t ordered(float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}
inline float unordered(uint32_t u) {
    u = (u & 0x80000000u) ? (u & 0x7fffffffu) : ~u;
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}

inline int32_t coarse_index(float v, float o, float inv_coarse, int32_t n) {
    const float q = std::floor((v - o) * inv_coarse);
    return int32_t(std::clamp(q, 0.0f, float(n - 1)));
}

// Splats dense point q (with normal nq) into sample (p, n, t1)'s map `cells`
// (G*G ordered depths), taking the minimum.
inline void splat_point(const RenderParams& r, const float* smp, const float* q, uint32_t* cells) {
    const V3 p = pose::load3(smp), z = pose::mul(pose::load3(smp + 3), -1.0f), t1 = pose::load3(smp + 6);
    const V3 t2 = pose::cross(z, t1);
    const V3 d = pose::sub(pose::load3(q), p);
    const float h = pose::dot(d, z);
    if (std::fabs(h) > r.cap || pose::dot(pose::load3(q + 3), z) > r.facing) return;
    const float half = float(r.G - 1) * 0.5f, rc = r.splat * r.inv_cell;
    const float fa = pose::dot(d, t1) * r.inv_cell + half, fb = pose::dot(d, t2) * r.inv_cell + half;
    const int32_t i0 = std::max(0, int32_t(std::ceil(fa - rc))), i1 = std::min(r.G - 1, int32_t(std::floor(fa + rc)));
    const int32_t j0 = std::max(0, int32_t(std::ceil(fb - rc))), j1 = std::min(r.G - 1, int32_t(std::floor(fb + rc)));
    const uint32_t v = ordered(h);
    for (int32_t j = j0; j <= j1; ++j)
        for (int32_t i = i0; i <= i1; ++i) {
            const float da = float(i) - fa, db = float(j) - fb;
            if (da * da + db * db <= rc * rc) {
                uint32_t& c = cells[j * r.G + i];
                c = std::min(c, v);
            }
        }
}

// A map's bilinear quads, what the scorer reads: entry (i, j), for i and j in
// [-1, G-1], holds the map at (i, j), (i+1, j), (i, j+1), (i+1, j+1), cap off the
// grid; (G+1)^2 entries of 4 floats, row-major in j. One vector read per sample
// instead of four gathers (lavapipe loops over the lanes for each gather: the
// score took 192 ms a touch with four, ~110 with one; docs/render_compare.md).
inline int32_t quad_side(int32_t G) { return G + 1; }

inline void make_quads(const float* map, int32_t G, float cap, float* q) {
    auto at = [&](int32_t i, int32_t j) { return i < 0 || j < 0 || i >= G || j >= G ? cap : map[j * G + i]; };
    const int32_t Q = quad_side(G);
    for (int32_t j = -1; j < G; ++j)
        for (int32_t i = -1; i < G; ++i) {
            float* t = q + 4 * ((j + 1) * Q + (i + 1));
            t[0] = at(i, j), t[1] = at(i + 1, j), t[2] = at(i, j + 1), t[3] = at(i + 1, j + 1);
        }
}

// Every map's quads: maps [S, G*G] -> [S, 4 (G+1)^2].
inline std::vector<float> quads_of_maps(const float* maps, int64_t S, int32_t G, float cap) {
    const size_t per = size_t(4 * quad_side(G) * quad_side(G));
    std::vector<float> q(size_t(S) * per);
    for (int64_t i = 0; i < S; ++i) make_quads(maps + size_t(i) * size_t(G) * size_t(G), G, cap, &q[size_t(i) * per]);
    return q;
}

// The spins [NS, 2]: cos and sin of 2 pi j / NS (the filter's hypotheses, SPEC 6).
inline std::vector<float> spin_table(int32_t NS) {
    std::vector<float> t;
    for (int32_t j = 0; j < NS; ++j) {
        const double a = 2 * M_PI * j / NS;
        t.push_back(float(std::cos(a)));
        t.push_back(float(std::sin(a)));
    }
    return t;
}

// A sample's map at fractional cell (fa, fb) from its quads: bilinear, cap outside the grid.
inline float quad_at(const float* q, int32_t G, float cap, float fa, float fb) {
    const float a0 = std::floor(fa), b0 = std::floor(fb);
    const float wa = fa - a0, wb = fb - b0;
    const int32_t i = int32_t(a0), j = int32_t(b0);
    const bool inside = i >= -1 && j >= -1 && i < G && j < G;
    const float* t = q + 4 * (inside ? (j + 1) * quad_side(G) + (i + 1) : 0);
    const float t0 = inside ? t[0] : cap, t1 = inside ? t[1] : cap, t2 = inside ? t[2] : cap, t3 = inside ? t[3] : cap;
    const float top = t0 * (1.0f - wa) + t1 * wa;
    const float bot = t2 * (1.0f - wa) + t3 * wa;
    return top * (1.0f - wb) + bot * wb;
}

// The scoring of one hypothesis: the measured indentation m [R, C] (cells of
// `win` mm, row-major; row r at v = (r - (R-1)/2) win along the sensor's y,
// column c at u along x) against the sample's map seen at spin (cs, sn),
// pressed `press` mm past its shallowest point in the window: predicted
// max(0, w_min + press - w), w_min from window_min (it depends on the map, the
// spin and the window only, so the scorer computes it once per window size and
// every touch reads it). `press` is the measured map's press (measured_press: a
// high percentile of its pressed cells, not its maximum, which the reader's
// noise and integration error inflate). The error e = m - predicted loses its
// best fit in the basis (least squares): the plane 1, r, c (the sensor's tilt,
// up to 10 degrees in our data, and the press's offset are not where the touch
// was; without it a tilted touch scored its own place below half the surface),
// and with `quadratic` also r^2, c^2, r c (the bowl that integrating a frame's
// noisy slopes leaves; it also hides the contact's own curvature). Returns
// -weight * sum (e - fit)^2 / (R C press^2) (0 when press is 0: no evidence).
struct ScoreParams {
    int32_t G, R, C;
    float inv_cell, win, cap, weight;  // inv_cell: float(1 / the maps' cell)
};

// The fit's basis over the window, centred so that it is orthogonal on a full grid
// (1; r' = r - hr; c' = c - hc; r'^2 - mr; c'^2 - mc; r' c', mr and mc the means of
// r'^2 and c'^2): each coefficient is its own projection, the inverse of its basis
// vector's squared norm times its sum with e. Computed on the host in double (shaders
// may not divide exactly) and pushed to the shader; 0 for a vector that vanishes (one
// row or column, two for a square) and for the quadratic ones without `quadratic`.
struct Basis {
    float inv_n, inv_r, inv_c, inv_rr, inv_cc, inv_rc, mr, mc;
};

inline Basis error_basis(int32_t R, int32_t C, bool quadratic) {
    const double hr = (R - 1) * 0.5, hc = (C - 1) * 0.5;
    double mr = 0, mc = 0;
    for (int32_t r = 0; r < R; ++r) mr += (r - hr) * (r - hr) / R;
    for (int32_t c = 0; c < C; ++c) mc += (c - hc) * (c - hc) / C;
    double n[6] = {};
    for (int32_t r = 0; r < R; ++r)
        for (int32_t c = 0; c < C; ++c) {
            const double a = r - hr, b = c - hc, v[6] = {1, a, b, a * a - mr, b * b - mc, a * b};
            for (int k = 0; k < 6; ++k) n[k] += v[k] * v[k];
        }
    auto inv = [](double x, bool on) { return on && x > 1e-9 ? float(1.0 / x) : 0.0f; };
    return {inv(n[0], true), inv(n[1], true), inv(n[2], true), inv(n[3], quadratic), inv(n[4], quadratic), inv(n[5], quadratic),
            float(mr), float(mc)};
}

constexpr int32_t kMaxWindowCells = 4096;

// The map's depth under window cell (r, c) at spin (cs, sn), from its quads (make_quads).
inline float window_depth(const ScoreParams& s, const float* quads, float cs, float sn, int32_t r, int32_t c) {
    const float half = float(s.G - 1) * 0.5f, hr = float(s.R - 1) * 0.5f, hc = float(s.C - 1) * 0.5f;
    const float u = (float(c) - hc) * s.win, v = (float(r) - hr) * s.win;
    const float a = u * cs - v * sn, b = u * sn + v * cs;
    return quad_at(quads, s.G, s.cap, a * s.inv_cell + half, b * s.inv_cell + half);
}

inline float window_min(const ScoreParams& s, const float* quads, float cs, float sn) {
    float wmin = s.cap;
    for (int32_t r = 0; r < s.R; ++r)
        for (int32_t c = 0; c < s.C; ++c) wmin = std::min(wmin, window_depth(s, quads, cs, sn, r, c));
    return wmin;
}

// One pass: the error's sums against each basis vector and its square, then the fit's
// share taken out by orthogonality, sum (e - fit)^2 = sum e^2 - sum_k (sum_k e)^2 / |b_k|^2
// (the fp32 cancellation is ~1e-7 of sum e^2; clamped at 0).
inline float score_hypothesis(const ScoreParams& s, const Basis& B, const float* quads, float cs, float sn, const float* m, float wmin,
                              float press) {
    if (!(press > 1e-6f)) return 0.0f;
    const float hr = float(s.R - 1) * 0.5f, hc = float(s.C - 1) * 0.5f;
    const float top = wmin + press;
    float s0 = 0.0f, sr = 0.0f, sc = 0.0f, srr = 0.0f, scc = 0.0f, src = 0.0f, s2 = 0.0f;
    for (int32_t r = 0; r < s.R; ++r)
        for (int32_t c = 0; c < s.C; ++c) {
            const float a = float(r) - hr, b = float(c) - hc;
            const float e = m[r * s.C + c] - std::max(0.0f, top - window_depth(s, quads, cs, sn, r, c));
            s0 += e;
            sr += e * a;
            sc += e * b;
            srr += e * (a * a - B.mr);
            scc += e * (b * b - B.mc);
            src += e * (a * b);
            s2 += e * e;
        }
    const float k0 = s0 * B.inv_n, kr = sr * B.inv_r, kc = sc * B.inv_c, krr = srr * B.inv_rr, kcc = scc * B.inv_cc, krc = src * B.inv_rc;
    const float err = std::max(0.0f, s2 - (k0 * s0 + kr * sr + kc * sc + krr * srr + kcc * scc + krc * src));
    return -s.weight * err / (float(s.R * s.C) * press * press);
}

// A measured map's press [mm]: the `pct` percentile (nearest rank) of its cells pressed
// deeper than 2 % of its deepest (0 for a map with no press). The maximum itself is the
// cell the reader's noise and integration error inflate most.
inline float measured_press(const float* m, int32_t n, double pct) {
    float deepest = 0.0f;
    for (int32_t k = 0; k < n; ++k) deepest = std::max(deepest, m[k]);
    if (!(deepest > 1e-6f)) return 0.0f;
    std::vector<float> v;
    for (int32_t i = 0; i < n; ++i)
        if (m[i] > 0.02f * deepest) v.push_back(m[i]);
    const int32_t k = int32_t(v.size()), rank = std::clamp(int32_t(std::ceil(pct / 100.0 * k)) - 1, 0, k - 1);
    std::nth_element(v.begin(), v.begin() + rank, v.end());
    return v[size_t(rank)];
}

}  // namespace vtloc::ops::book
