#pragma once
// The gel's shape from a frame (SPEC 9, docs/gel_shape.md), per pixel, as the
// shaders compute it: the CPU references of ops gel_gradient and masked_poisson,
// and what engine/sensor/gel_shape runs on the CPU. fp32 in the shaders' order.
#include <algorithm>
#include <cmath>
#include <cstdint>

namespace vtloc::ops::gel {

// The table cell of a colour change v (an integer grey-level difference, so exact in fp32).
inline int cell_of(float v, int n) {
    const float q = std::floor((v + 256.0f) * float(n) / 512.0f);
    return int(std::clamp(q, 0.0f, float(n - 1)));
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
inline void masked_poisson(const float* grad, const float* mask, int H, int W, int iterations, float omega, float* z) {
    const uint64_t HW = uint64_t(H) * uint64_t(W);
    std::fill(z, z + HW, 0.0f);
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

}  // namespace vtloc::ops::gel
