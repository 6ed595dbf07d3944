#pragma once
// The gel's contact mask (SPEC 9, docs/gel_shape.md step 4): the CPU reference of op
// gel_contact_mask and what engine/sensor/gel_shape runs on the CPU. The slope is fp32 in the
// shader's order; the morphology, hole fill and labelling are integer and exact, with
// OpenCV's conventions (the tests compare against cv::morphologyEx, cv::floodFill and
// cv::connectedComponentsWithStats): a structuring element only reads pixels inside the image,
// holes are background not 4-connected to the border, and the largest 4-connected piece wins
// ties by its first pixel in raster order.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace vtloc::ops::gel {

// |grad| at pixel q, as the shader computes it (no hypot there; fp32 throughout).
inline float slope_at(const float* grad, uint64_t q) {
    const float a = grad[2 * q], b = grad[2 * q + 1];
    const float s = a * a + b * b;
    return std::sqrt(s);
}

// The 3x3 mean of |grad| around (r, c), edge pixels repeated: rows summed left to right, then
// top to bottom, times 1/9 (a multiply, not a division: a shader's division is not exact).
inline float slope_mean(const float* grad, int H, int W, int r, int c) {
    float rows[3];
    for (int dy = -1; dy <= 1; ++dy) {
        const uint64_t y = uint64_t(std::min(std::max(r + dy, 0), H - 1));
        float s = 0.0f;
        for (int dx = -1; dx <= 1; ++dx) s += slope_at(grad, y * uint64_t(W) + uint64_t(std::min(std::max(c + dx, 0), W - 1)));
        rows[dy + 1] = s;
    }
    const float sum = (rows[0] + rows[1]) + rows[2];
    return sum * (1.0f / 9.0f);
}

// Half the width of the disc of radius r (x^2 + y^2 <= r^2) in its row dy.
inline int disc_half_width(int r, int dy) {
    int w = 0;
    while ((w + 1) * (w + 1) + dy * dy <= r * r) ++w;
    return w;
}

// Dilation (value 1) or erosion (value 0) by the disc: a pixel takes `value` where any disc
// neighbour inside the image has it.
inline std::vector<uint8_t> morph(const std::vector<uint8_t>& m, int H, int W, int r, uint8_t value) {
    std::vector<uint8_t> out(m.size());
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            bool hit = false;
            for (int dy = -r; dy <= r && !hit; ++dy) {
                const int w = disc_half_width(r, dy), yy = y + dy;
                if (yy < 0 || yy >= H) continue;
                for (int xx = std::max(x - w, 0); xx <= std::min(x + w, W - 1) && !hit; ++xx) hit = m[size_t(yy) * W + size_t(xx)] == value;
            }
            out[size_t(y) * W + size_t(x)] = hit ? value : uint8_t(1 - value);
        }
    return out;
}

// The 4-connected piece of pixels equal to m[seed] that holds seed, as indices (a plain flood).
inline std::vector<size_t> piece(const std::vector<uint8_t>& m, int H, int W, size_t seed, std::vector<uint8_t>& seen) {
    std::vector<size_t> out{seed};
    seen[seed] = 1;
    for (size_t k = 0; k < out.size(); ++k) {
        const size_t q = out[k];
        const int y = int(q / size_t(W)), x = int(q % size_t(W));
        const size_t nb[4] = {q - size_t(W), q + size_t(W), q - 1, q + 1};
        const bool ok[4] = {y > 0, y + 1 < H, x > 0, x + 1 < W};
        for (int i = 0; i < 4; ++i)
            if (ok[i] && !seen[nb[i]] && m[nb[i]] == m[seed]) seen[nb[i]] = 1, out.push_back(nb[i]);
    }
    return out;
}

// m with its holes filled: background that no 4-connected background path joins to the border.
inline std::vector<uint8_t> fill_holes(std::vector<uint8_t> m, int H, int W) {
    std::vector<uint8_t> outside(m.size(), 0);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t q = size_t(y) * W + size_t(x);
            if ((y == 0 || x == 0 || y == H - 1 || x == W - 1) && !m[q] && !outside[q]) piece(m, H, W, q, outside);
        }
    for (size_t q = 0; q < m.size(); ++q) m[q] = m[q] || !outside[q];
    return m;
}

// The contact (0/1, [H, W]) from the indentation's gradient [H, W, 2]: the 3x3 mean slope above
// `threshold`; closed by the disc of close_radius, holes filled, opened by the disc of open_radius
// (0: no closing / opening); the largest 4-connected piece (the first in raster order among
// equals), its holes filled. Closing and filling come first: a shallow press's steep ring is
// thinner than the opening's disc, and only its filled disc survives the opening.
inline std::vector<uint8_t> contact_mask(const float* grad, int H, int W, float threshold, int close_radius, int open_radius) {
    std::vector<uint8_t> m(size_t(H) * size_t(W));
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) m[size_t(y) * W + size_t(x)] = slope_mean(grad, H, W, y, x) > threshold;
    if (close_radius > 0) m = morph(morph(m, H, W, close_radius, 1), H, W, close_radius, 0);
    m = fill_holes(std::move(m), H, W);
    if (open_radius > 0) m = morph(morph(m, H, W, open_radius, 0), H, W, open_radius, 1);
    std::vector<uint8_t> seen(m.size(), 0);
    std::vector<size_t> best;
    for (size_t q = 0; q < m.size(); ++q)
        if (m[q] && !seen[q]) {
            std::vector<size_t> p = piece(m, H, W, q, seen);
            if (p.size() > best.size()) best = std::move(p);  // raster order: ties keep the first
        }
    std::vector<uint8_t> out(m.size(), 0);
    for (size_t q : best) out[q] = 1;
    return fill_holes(std::move(out), H, W);
}

}  // namespace vtloc::ops::gel
