#pragma once
// The nearest surface point facing a gel, at any distance (a k-d tree over the
// filter's dense points). The lookup grid names points only within its band
// (a few mm); the refinement's registration step (tracker.cpp) needs where a
// touch carried 10-20 mm off by a pose error would land.
#include <cstdint>
#include <limits>
#include <vector>

namespace vtloc::track {

class NearestFacing {
public:
    NearestFacing() = default;
    // dense [D, 6]: point, outward unit normal; kept by pointer (the Surface's own table).
    explicit NearestFacing(const std::vector<float>& dense);
    // The index of the dense point nearest q whose outward normal n has n . z <= max_dot
    // (z: the gel's axis, into the object) and whose squared distance is below max_d2; -1
    // where none does or the tree is empty.
    int32_t query(const float q[3], const float z[3], float max_dot,
                  float max_d2 = std::numeric_limits<float>::infinity()) const;
    // This tree over `dense`, a copy of the table it was built on (another Surface holding the
    // same points): the order copied, not built again. Throws where the sizes differ.
    NearestFacing rebound(const std::vector<float>& dense) const;
    bool empty() const { return order_.empty(); }
    const float* point(int32_t i) const { return dense_ + int64_t(i) * 6; }  // point, normal

private:
    const float* dense_ = nullptr;
    std::vector<int32_t> order_;  // the points, each subrange's median at its middle
    std::vector<uint8_t> axis_;   // per middle position: the axis its subrange was split on
    std::vector<float> node_;     // [D, 6] the points in order_'s order (point, normal)
    std::vector<float> normals_;  // [D, 6] per middle position: its subrange's normals' least and most per axis
    void build(int64_t lo, int64_t hi);
    void search(int64_t lo, int64_t hi, const float q[3], const float z[3], float max_dot, float off[3], int32_t& best,
                float& best_d2) const;
};

}  // namespace vtloc::track
