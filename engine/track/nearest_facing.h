#pragma once
// The nearest surface point facing a gel, at any distance (a k-d tree over the
// filter's dense points). The lookup grid names points only within its band
// (a few mm); the refinement's registration step (tracker.cpp) needs where a
// touch carried 10-20 mm off by a pose error would land.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "engine/track/lazy_index.h"

namespace vtloc::track {

class NearestFacing {
public:
    NearestFacing() = default;
    // dense [D, 6]: point, outward unit normal. The tree keeps its own copy (in its order), so
    // it holds no pointer into the table and may outlive it or be shared.
    explicit NearestFacing(const std::vector<float>& dense);
    struct Match {
        int32_t index = -1;            // the dense point's row; -1: none
        const float* point = nullptr;  // its point and normal (the tree's copy)
    };
    // The dense point nearest q whose outward normal n has n . z <= max_dot (z: the gel's
    // axis, into the object) and whose squared distance is below max_d2 (ties: the lowest
    // index); none where no point does or the tree is empty.
    Match query(const float q[3], const float z[3], float max_dot, float max_d2 = std::numeric_limits<float>::infinity()) const;
    bool empty() const { return order_.empty(); }
    // Host bytes the tree holds.
    uint64_t bytes() const { return 4 * (order_.size() + node_.size() + normals_.size()) + axis_.size(); }

private:
    std::vector<int32_t> order_;  // the points, each subrange's median at its middle
    std::vector<float> node_;     // [D, 6] the points in order_'s order (point, normal)
    // Per internal node (heap numbered: the root 0, node k's halves 2k + 1 and 2k + 2): the
    // axis its subrange was split on, and its subrange's normals' least and most per axis.
    std::vector<uint8_t> axis_;
    std::vector<float> normals_;
    void build(const float* dense, int64_t lo, int64_t hi, size_t node);
    void search(int64_t lo, int64_t hi, size_t node, const float q[3], const float z[3], float max_dot, float off[3],
                int64_t& best, float& best_d2) const;
};

// A NearestFacing made on first use: only a window that fits poorly registers (the rescue,
// the deep search), so a tracker on a tour it follows should not pay for the tree at
// construction (docs/multitouch.md, "Registration").
using LazyNearestFacing = LazyIndex<NearestFacing>;

}  // namespace vtloc::track
