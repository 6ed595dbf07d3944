#include "engine/track/nearest_facing.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vtloc::track {

namespace {
constexpr int64_t kLeaf = 8;
}

NearestFacing::NearestFacing(const std::vector<float>& dense) {
    const int64_t D = int64_t(dense.size() / 6);
    order_.resize(size_t(D));
    for (int64_t i = 0; i < D; ++i) order_[size_t(i)] = int32_t(i);
    build(dense.data(), 0, D, 0);
    // The points in the tree's order: a subtree's points are contiguous, so a search reads
    // memory in runs instead of jumping through the table by index.
    node_.resize(size_t(D) * 6);
    for (int64_t p = 0; p < D; ++p) std::copy_n(&dense[size_t(order_[size_t(p)]) * 6], 6, &node_[size_t(p) * 6]);
}

// Split on the subrange's widest axis at its median: the tree stays balanced on thin,
// long objects where cycling the axes would cut the short ones.
void NearestFacing::build(const float* dense, int64_t lo, int64_t hi, size_t node) {
    if (hi - lo <= kLeaf) return;
    // Bounds on the subrange's points (0..2) and normals (3..5).
    float mn[6], mx[6];
    std::fill_n(mn, 6, std::numeric_limits<float>::max());
    std::fill_n(mx, 6, -std::numeric_limits<float>::max());
    for (int64_t i = lo; i < hi; ++i)
        for (int k = 0; k < 6; ++k) {
            const float v = dense[size_t(order_[size_t(i)]) * 6 + size_t(k)];
            mn[k] = std::min(mn[k], v), mx[k] = std::max(mx[k], v);
        }
    uint8_t a = 0;
    for (uint8_t k = 1; k < 3; ++k)
        if (mx[k] - mn[k] > mx[a] - mn[a]) a = k;
    const int64_t mid = (lo + hi) / 2;
    if (axis_.size() <= node) axis_.resize(node + 1), normals_.resize((node + 1) * 6);
    std::copy_n(mn + 3, 3, &normals_[node * 6]);
    std::copy_n(mx + 3, 3, &normals_[node * 6 + 3]);
    std::nth_element(order_.begin() + lo, order_.begin() + mid, order_.begin() + hi, [&](int32_t x, int32_t y) {
        return dense[size_t(x) * 6 + a] < dense[size_t(y) * 6 + a];
    });
    axis_[node] = a;
    build(dense, lo, mid, 2 * node + 1);
    build(dense, mid + 1, hi, 2 * node + 2);
}

// off: the query's distance to the subtree's box along each axis, from the splits on the way
// down (0 where none bounds it). Summed in the order the points' distances are, the square
// never exceeds any point's in the box (float rounding is monotone; track/ is built without
// FMA contraction, engine/CMakeLists.txt), so a box farther than the best is skipped whole,
// and the answer is the brute force's, ties included.
void NearestFacing::search(int64_t lo, int64_t hi, size_t node, const float q[3], const float z[3], float max_dot, float off[3],
                           int64_t& best, float& best_d2) const {
    auto visit = [&](int64_t pos) {
        const float* p = &node_[size_t(pos) * 6];
        if (p[3] * z[0] + p[4] * z[1] + p[5] * z[2] > max_dot) return;
        const float dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2], d2 = dx * dx + dy * dy + dz * dz;
        if (d2 < best_d2 || (d2 == best_d2 && best >= 0 && order_[size_t(pos)] < order_[size_t(best)])) best = pos, best_d2 = d2;
    };
    if (hi - lo <= kLeaf) {
        for (int64_t pos = lo; pos < hi; ++pos) visit(pos);
        return;
    }
    const int64_t mid = (lo + hi) / 2;
    // Every normal of the subtree facing away: its least n . z, bounded from the normals' box
    // term by term in the order visit sums them, exceeds max_dot.
    const float* nb = &normals_[node * 6];
    float least = 0;
    for (int k = 0; k < 3; ++k) least += std::min(nb[k] * z[k], nb[k + 3] * z[k]);
    if (least > max_dot) return;
    const uint8_t a = axis_[node];
    const float diff = q[a] - node_[size_t(mid) * 6 + a];
    visit(mid);
    const bool left_first = diff < 0;
    if (left_first)
        search(lo, mid, 2 * node + 1, q, z, max_dot, off, best, best_d2);
    else
        search(mid + 1, hi, 2 * node + 2, q, z, max_dot, off, best, best_d2);
    const float kept = off[a];
    off[a] = std::abs(diff);
    if (off[0] * off[0] + off[1] * off[1] + off[2] * off[2] <= best_d2) {
        if (left_first)
            search(mid + 1, hi, 2 * node + 2, q, z, max_dot, off, best, best_d2);
        else
            search(lo, mid, 2 * node + 1, q, z, max_dot, off, best, best_d2);
    }
    off[a] = kept;
}

NearestFacing::Match NearestFacing::query(const float q[3], const float z[3], float max_dot, float max_d2) const {
    int64_t best = -1;  // a position in the tree's order
    float best_d2 = max_d2;
    float off[3] = {0, 0, 0};
    if (!order_.empty()) search(0, int64_t(order_.size()), 0, q, z, max_dot, off, best, best_d2);
    if (best < 0) return {};
    return {order_[size_t(best)], &node_[size_t(best) * 6]};
}

}  // namespace vtloc::track
