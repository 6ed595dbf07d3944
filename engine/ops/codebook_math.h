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

// A sample's map at fractional cell (fa, fb): bilinear, cap outside the grid.
inline float book_at(const float* map, int32_t G, float cap, float fa, float fb) {
    const float a0 = std::floor(fa), b0 = std::floor(fb);
    const float wa = fa - a0, wb = fb - b0;
    const int32_t i = int32_t(a0), j = int32_t(b0);
    auto at = [&](int32_t ii, int32_t jj) { return ii < 0 || jj < 0 || ii >= G || jj >= G ? cap : map[jj * G + ii]; };
    const float top = at(i, j) * (1.0f - wa) + at(i + 1, j) * wa;
    const float bot = at(i, j + 1) * (1.0f - wa) + at(i + 1, j + 1) * wa;
    return top * (1.0f - wb) + bot * wb;
}

// The scoring of one hypothesis: the measured indentation m [R, C] (cells of
// `win` mm, row-major; row r at v = (r - (R-1)/2) win along the sensor's y,
// column c at u along x) against the sample's map seen at spin (cs, sn),
// pressed until its deepest cell matches m's deepest: predicted
// max(0, w_min + depth - w). The error e = m - predicted loses its best plane
// over the window (least squares in 1, r, c: the sensor's tilt, up to 10 degrees
// in our data, and the press's offset are not where the touch was; without this
// a tilted touch scored its own place below half the surface). Returns
// -weight * sum (e - plane)^2 / (R C depth^2) (0 when m holds no press).
struct ScoreParams {
    int32_t G, R, C;
    float inv_cell, win, cap, weight;  // inv_cell: float(1 / the maps' cell)
};

// 1 / sum over the window of (r - hr)^2, and of (c - hc)^2 (0 for one row or column),
// and 1 / (R C): the plane's basis 1, r - hr, c - hc is orthogonal on a full grid, so
// each coefficient is its own projection. Computed on the host (shaders may not divide
// exactly) and pushed to the shader.
inline float inv_row_moment(int32_t R, int32_t C) {
    return R > 1 ? float(12.0 / (double(C) * double(R) * (double(R) * double(R) - 1.0))) : 0.0f;
}
inline float inv_count(int32_t R, int32_t C) { return float(1.0 / (double(R) * double(C))); }

constexpr int32_t kMaxWindowCells = 4096;

inline float score_hypothesis(const ScoreParams& s, const float* map, float cs, float sn, const float* m) {
    const float half = float(s.G - 1) * 0.5f, hr = float(s.R - 1) * 0.5f, hc = float(s.C - 1) * 0.5f;
    float depth = 0.0f;
    for (int32_t k = 0; k < s.R * s.C; ++k) depth = std::max(depth, m[k]);
    if (!(depth > 1e-6f)) return 0.0f;
    float seen[kMaxWindowCells];
    float wmin = s.cap;
    for (int32_t r = 0; r < s.R; ++r)
        for (int32_t c = 0; c < s.C; ++c) {
            const float u = (float(c) - hc) * s.win, v = (float(r) - hr) * s.win;
            const float a = u * cs - v * sn, b = u * sn + v * cs;
            const float w = book_at(map, s.G, s.cap, a * s.inv_cell + half, b * s.inv_cell + half);
            seen[r * s.C + c] = w;
            wmin = std::min(wmin, w);
        }
    float s0 = 0.0f, sr = 0.0f, sc = 0.0f;
    for (int32_t r = 0; r < s.R; ++r)
        for (int32_t c = 0; c < s.C; ++c) {
            const float e = m[r * s.C + c] - std::max(0.0f, wmin + depth - seen[r * s.C + c]);
            s0 += e;
            sr += e * (float(r) - hr);
            sc += e * (float(c) - hc);
        }
    const float k0 = s0 * inv_count(s.R, s.C), kr = sr * inv_row_moment(s.R, s.C), kc = sc * inv_row_moment(s.C, s.R);
    float err = 0.0f;
    for (int32_t r = 0; r < s.R; ++r)
        for (int32_t c = 0; c < s.C; ++c) {
            const float e = m[r * s.C + c] - std::max(0.0f, wmin + depth - seen[r * s.C + c]);
            const float f = e - (k0 + kr * (float(r) - hr) + kc * (float(c) - hc));
            err += f * f;
        }
    return -s.weight * err / (float(s.R * s.C) * depth * depth);
}

}  // namespace vtloc::ops::book
