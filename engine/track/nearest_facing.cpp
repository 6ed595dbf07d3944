#include "engine/track/nearest_facing.h"

#include <algorithm>
#include <limits>
#include <string>

#include "base/error.h"

namespace vtloc::track {

namespace {
constexpr int64_t kLeaf = 8;
}

NearestFacing::NearestFacing(const std::vector<float>& dense) : dense_(dense.data()) {
    const int64_t D = int64_t(dense.size() / 6);
    order_.resize(size_t(D));
    for (int64_t i = 0; i < D; ++i) order_[size_t(i)] = int32_t(i);
    axis_.assign(size_t(D), 0);
    build(0, D);
}

NearestFacing NearestFacing::rebound(const std::vector<float>& dense) const {
    if (dense.size() != order_.size() * 6)
        throw Error("nearest facing: a tree over " + std::to_string(order_.size()) + " points cannot be rebound to " +
                    std::to_string(dense.size() / 6));
    NearestFacing t = *this;
    t.dense_ = dense.data();
    return t;
}

// Split on the subrange's widest axis at its median: the tree stays balanced on thin,
// long objects where cycling the axes would cut the short ones.
void NearestFacing::build(int64_t lo, int64_t hi) {
    if (hi - lo <= kLeaf) return;
    float mn[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(), std::numeric_limits<float>::max()};
    float mx[3] = {-mn[0], -mn[1], -mn[2]};
    for (int64_t i = lo; i < hi; ++i)
        for (int k = 0; k < 3; ++k) {
            const float v = dense_[size_t(order_[size_t(i)]) * 6 + size_t(k)];
            mn[k] = std::min(mn[k], v), mx[k] = std::max(mx[k], v);
        }
    uint8_t a = 0;
    for (uint8_t k = 1; k < 3; ++k)
        if (mx[k] - mn[k] > mx[a] - mn[a]) a = k;
    const int64_t mid = (lo + hi) / 2;
    std::nth_element(order_.begin() + lo, order_.begin() + mid, order_.begin() + hi, [&](int32_t x, int32_t y) {
        return dense_[size_t(x) * 6 + a] < dense_[size_t(y) * 6 + a];
    });
    axis_[size_t(mid)] = a;
    build(lo, mid);
    build(mid + 1, hi);
}

void NearestFacing::search(int64_t lo, int64_t hi, const float q[3], const float z[3], float max_dot, int32_t& best,
                           float& best_d2) const {
    auto visit = [&](int32_t i) {
        const float* p = dense_ + size_t(i) * 6;
        if (p[3] * z[0] + p[4] * z[1] + p[5] * z[2] > max_dot) return;
        const float dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2], d2 = dx * dx + dy * dy + dz * dz;
        if (d2 < best_d2 || (d2 == best_d2 && i < best)) best = i, best_d2 = d2;
    };
    if (hi - lo <= kLeaf) {
        for (int64_t i = lo; i < hi; ++i) visit(order_[size_t(i)]);
        return;
    }
    const int64_t mid = (lo + hi) / 2;
    const int32_t m = order_[size_t(mid)];
    const uint8_t a = axis_[size_t(mid)];
    const float diff = q[a] - dense_[size_t(m) * 6 + a];
    visit(m);
    if (diff < 0) {
        search(lo, mid, q, z, max_dot, best, best_d2);
        if (diff * diff <= best_d2) search(mid + 1, hi, q, z, max_dot, best, best_d2);
    } else {
        search(mid + 1, hi, q, z, max_dot, best, best_d2);
        if (diff * diff <= best_d2) search(lo, mid, q, z, max_dot, best, best_d2);
    }
}

int32_t NearestFacing::query(const float q[3], const float z[3], float max_dot, float max_d2) const {
    int32_t best = -1;
    float best_d2 = max_d2;
    if (!order_.empty()) search(0, int64_t(order_.size()), q, z, max_dot, best, best_d2);
    return best;
}

}  // namespace vtloc::track
