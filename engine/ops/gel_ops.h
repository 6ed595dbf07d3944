#pragma once
// The gel's shape from a frame (SPEC 9, docs/gel_shape.md), per pixel, as the
// shaders compute it: the CPU references of ops gel_gradient and masked_poisson,
// and what engine/sensor/gel_shape runs on the CPU. fp32 in the shaders' order.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace vtloc::ops::gel {

// The table cell of a colour change v (an integer grey-level difference, so exact in fp32):
// floor((v + 256) n / 512) clamped to [0, n - 1], as the shader computes it. Without a call to
// floor (x86-64's baseline SSE2 has no rounding instruction; building the gradient table
// calls this 51 million times): the same cell for every finite v, checked over every finite
// float for n = 2, 3, 64 and 256, and by a test on a stride of them.
inline int cell_of(float v, int n) {
    const float x = (v + 256.0f) * float(n) / 512.0f;
    if (!(x >= 0.0f)) return 0;
    if (x >= float(n - 1)) return n - 1;
    return int(x);  // truncation is floor for x >= 0
}

// The gradient the tables give pixel (r, c) for colour change d[3]: the four nearest tiles'
// tables blended by the pixel's place between their centres. lut: [ty * tx][n^3][2].
inline void table_gradient(const float* lut, int n, int ty, int tx, int H, int W, int r, int c, const float d[3],
                           float& g_row, float& g_col) {
    const uint32_t cell = (uint32_t(cell_of(d[0], n)) * uint32_t(n) + uint32_t(cell_of(d[1], n))) * uint32_t(n) +
                          uint32_t(cell_of(d[2], n));
    const float fy = std::clamp((float(r) + 0.5f) * float(ty) / float(H) - 0.5f, 0.0f, float(ty - 1));
    const float fx = std::clamp((float(c) + 0.5f) * float(tx) / float(W) - 0.5f, 0.0f, float(tx - 1));
    const int a0 = ty > 1 ? std::min(int(fy), ty - 2) : 0, b0 = tx > 1 ? std::min(int(fx), tx - 2) : 0;
    const float wy = fy - float(a0), wx = fx - float(b0);
    const uint64_t n3 = uint64_t(n) * uint64_t(n) * uint64_t(n);
    g_row = 0, g_col = 0;
    for (int da = 0; da < 2; ++da)
        for (int db = 0; db < 2; ++db) {
            const float w = (da ? wy : 1.0f - wy) * (db ? wx : 1.0f - wx);
            const int a = std::min(a0 + da, ty - 1), b = std::min(b0 + db, tx - 1);
            const float* g = &lut[((uint64_t(a) * uint64_t(tx) + uint64_t(b)) * n3 + cell) * 2];
            g_row += w * g[0];
            g_col += w * g[1];
        }
}

// The indentation's gradient at (r, c): the tables' answer for the colour change (frame - empty)
// less their answer for none (the untouched gel there). Where that slope is gentle (|g| <= gentle,
// gentle > 0), the shading linearised about the untouched gel instead: g = L d with the pixel's
// 2 x 3 matrix L (row then column; `linear`: [H, W, 6]), as the tables' cells are too coarse
// for the small colour changes of gentle slopes. frame, empty: [H, W, 3].
inline void indentation_gradient(const float* lut, int n, int ty, int tx, int H, int W, const float* frame,
                                 const float* empty, const float* linear, float gentle, int r, int c, float& g_row,
                                 float& g_col) {
    const uint64_t p = uint64_t(r) * uint64_t(W) + uint64_t(c);
    const float d[3] = {frame[3 * p] - empty[3 * p], frame[3 * p + 1] - empty[3 * p + 1], frame[3 * p + 2] - empty[3 * p + 2]};
    const float none[3] = {0, 0, 0};
    float zr = 0, zc = 0;
    table_gradient(lut, n, ty, tx, H, W, r, c, d, g_row, g_col);
    table_gradient(lut, n, ty, tx, H, W, r, c, none, zr, zc);
    g_row -= zr;
    g_col -= zc;
    const float m2 = g_row * g_row + g_col * g_col;
    if (gentle > 0.0f && m2 <= gentle * gentle) {
        const float* L = &linear[6 * p];
        g_row = (L[0] * d[0] + L[1] * d[1]) + L[2] * d[2];
        g_col = (L[3] * d[0] + L[4] * d[1]) + L[5] * d[2];
    }
}

// div(g) at (r, c) with numpy.gradient's differences (central inside, one-sided at the border).
// grad: [H, W, 2] (row, col).
inline float divergence(const float* grad, int H, int W, int r, int c) {
    auto g = [&](int rr, int cc, int k) { return grad[(uint64_t(rr) * uint64_t(W) + uint64_t(cc)) * 2 + uint64_t(k)]; };
    const float dr = H == 1 ? 0.0f
                     : r == 0 ? g(1, c, 0) - g(0, c, 0)
                     : r == H - 1 ? g(r, c, 0) - g(r - 1, c, 0)
                                  : 0.5f * (g(r + 1, c, 0) - g(r - 1, c, 0));
    const float dc = W == 1 ? 0.0f
                     : c == 0 ? g(r, 1, 1) - g(r, 0, 1)
                     : c == W - 1 ? g(r, c, 1) - g(r, c - 1, 1)
                                  : 0.5f * (g(r, c + 1, 1) - g(r, c - 1, 1));
    return dr + dc;
}

// Red-black SOR for lap(z) = div(grad) where mask > 0.5, z = 0 elsewhere in the image: `iterations`
// sweeps (red, (r + c) even, then black), z zeroed first. The image's own border is free, not
// zero: a neighbour beyond it is a ghost continuing the pixel's gradient (z -/+ g), since a
// contact larger than the window (a large object pressed gently) goes on beyond the frame.
// Within a colour the updates are independent.
// start: the first guess ([H, W]; nullptr: zeros), taken where the solve updates, 0 elsewhere.
inline void masked_poisson(const float* grad, const float* mask, int H, int W, int iterations, float omega, float* z,
                           const float* start = nullptr) {
    const uint64_t HW = uint64_t(H) * uint64_t(W);
    const bool pinned = H > 1 || W > 1;
    for (uint64_t p = 0; p < HW; ++p) z[p] = start && pinned && mask[p] > 0.5f ? start[p] : 0.0f;
    for (int it = 0; it < iterations; ++it)
        for (int colour = 0; colour < 2; ++colour)
            for (int r = 0; r < H; ++r)
                for (int c = (r + colour) % 2; c < W; c += 2) {
                    const uint64_t p = uint64_t(r) * uint64_t(W) + uint64_t(c);
                    if (!(mask[p] > 0.5f)) continue;
                    const float gr = grad[2 * p], gc = grad[2 * p + 1];
                    const int inside = (r > 0) + (r + 1 < H) + (c > 0) + (c + 1 < W);
                    if (inside == 0) continue;  // a 1 x 1 image: nothing pins it
                    const float nb = ((r > 0 ? z[p - uint64_t(W)] : -gr) + (r + 1 < H ? z[p + uint64_t(W)] : gr)) +
                                     ((c > 0 ? z[p - 1] : -gc) + (c + 1 < W ? z[p + 1] : gc));
                    z[p] = (1.0f - omega) * z[p] + omega * ((nb - divergence(grad, H, W, r, c)) / float(inside));
                }
}

// Op mean_pool2: each output pixel the mean of its block of up to 2 x 2 input pixels (an odd last
// row or column: the pixels it has), per channel; x: [H, W, C] -> [ceil(H/2), ceil(W/2), C]. The
// solve's coarse grids: the gradient keeps its value (a slope per pixel becomes one per two
// pixels, see poisson_prolong), the mask its > 0.5 rule (3 of 4 pixels in the contact).
inline void mean_pool2(const float* x, int H, int W, int C, float* out) {
    const int h = (H + 1) / 2, w = (W + 1) / 2;
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c)
            for (int k = 0; k < C; ++k) {
                auto at = [&](int rr, int cc) { return x[(uint64_t(rr) * uint64_t(W) + uint64_t(cc)) * uint64_t(C) + uint64_t(k)]; };
                const bool down = 2 * r + 1 < H, right = 2 * c + 1 < W;
                const float top = right ? at(2 * r, 2 * c) + at(2 * r, 2 * c + 1) : at(2 * r, 2 * c);
                const float bottom = !down ? 0.0f : right ? at(2 * r + 1, 2 * c) + at(2 * r + 1, 2 * c + 1) : at(2 * r + 1, 2 * c);
                out[(uint64_t(r) * uint64_t(w) + uint64_t(c)) * uint64_t(C) + uint64_t(k)] =
                    (top + bottom) / float((1 + int(down)) * (1 + int(right)));
            }
}

// Op poisson_prolong: a coarse solve's answer zc [h, w] as the start of the solve on the grid it
// halved ([H, W], h = ceil(H/2), w = ceil(W/2)): bilinear between the coarse pixels' centres
// (clamped at the edges), times 2 (a coarse pixel is two of these, and z is in pixels), 0 where
// mask <= 0.5.
inline float prolong_at(const float* zc, int h, int w, int r, int c) {
    const float fy = std::clamp(0.5f * float(r) - 0.25f, 0.0f, float(h - 1));
    const float fx = std::clamp(0.5f * float(c) - 0.25f, 0.0f, float(w - 1));
    const int a = h > 1 ? std::min(int(fy), h - 2) : 0, b = w > 1 ? std::min(int(fx), w - 2) : 0;
    const int a1 = std::min(a + 1, h - 1), b1 = std::min(b + 1, w - 1);
    const float wy = fy - float(a), wx = fx - float(b);
    auto z = [&](int rr, int cc) { return zc[uint64_t(rr) * uint64_t(w) + uint64_t(cc)]; };
    const float top = (1.0f - wx) * z(a, b) + wx * z(a, b1), bottom = (1.0f - wx) * z(a1, b) + wx * z(a1, b1);
    return 2.0f * ((1.0f - wy) * top + wy * bottom);
}

inline void poisson_prolong(const float* zc, int h, int w, const float* mask, int H, int W, float* z0) {
    for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c) {
            const uint64_t p = uint64_t(r) * uint64_t(W) + uint64_t(c);
            z0[p] = mask[p] > 0.5f ? prolong_at(zc, h, w, r, c) : 0.0f;
        }
}

// How many times the solve halves an H x W grid for its coarse start: at most `levels`, while the
// coarser grid keeps both sides >= 8 pixels (below that a coarse answer says little).
inline int poisson_levels(int H, int W, int levels) {
    int n = 0;
    while (n < levels && (H + 1) / 2 >= 8 && (W + 1) / 2 >= 8) H = (H + 1) / 2, W = (W + 1) / 2, ++n;
    return n;
}

// The solve from a coarse start (the graph engine/sensor/gel_shape_gpu builds, op for op): the
// gradient and mask halved poisson_levels(H, W, levels) times, the coarsest solved from zeros
// with coarse_iterations sweeps, each finer grid started from the coarser answer (prolonged),
// with coarse_iterations sweeps, and the full grid with `iterations`. levels 0: the plain solve.
inline void masked_poisson_multilevel(const float* grad, const float* mask, int H, int W, int levels, int iterations,
                                      int coarse_iterations, float omega, float* z) {
    const int n = poisson_levels(H, W, levels);
    if (n == 0) return masked_poisson(grad, mask, H, W, iterations, omega, z);
    const int h = (H + 1) / 2, w = (W + 1) / 2;
    std::vector<float> g2(size_t(h) * size_t(w) * 2), m2(size_t(h) * size_t(w)), z2(m2.size()), start(size_t(H) * size_t(W));
    mean_pool2(grad, H, W, 2, g2.data());
    mean_pool2(mask, H, W, 1, m2.data());
    masked_poisson_multilevel(g2.data(), m2.data(), h, w, n - 1, coarse_iterations, coarse_iterations, omega, z2.data());
    poisson_prolong(z2.data(), h, w, mask, H, W, start.data());
    masked_poisson(grad, mask, H, W, iterations, omega, z, start.data());
}

}  // namespace vtloc::ops::gel
