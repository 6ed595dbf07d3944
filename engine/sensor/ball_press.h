#pragma once
// A ball pressed into the gel: where a frame shows the contact, and the
// indentation a ball of known size makes for a contact circle. The reality
// check (engine/sim) and `vtloc calibrate` (calibrate.h) share both.
#include <cstdint>
#include <vector>

namespace vtloc::sensor {

// The contact as an image shows it: diff = sum over channels of |frame -
// empty| (the frame's own empty frame), Gaussian-smoothed (sigma 1.5 px);
// pixels above kContactFraction of the smoothed maximum; the largest
// 8-connected component's centroid and equivalent-area radius sqrt(A/pi).
struct DetectedContact {
    bool found = false;
    double cx = 0, cy = 0;  // column, row (pixels)
    double radius = 0;      // pixels
};
inline constexpr double kContactFraction = 0.25;
DetectedContact detect_contact(const std::vector<uint8_t>& frame, const std::vector<uint8_t>& empty, int height,
                               int width);

// A contact circle of radius r (mm) left by a ball of radius ball_mm: radii at
// or past the ball's own are presses to its full width, so the sphere is
// enlarged to 1.05 r (data/gelsight/README.md) and the depth stays defined.
struct BallCap {
    double sphere_mm = 0, depth_mm = 0;
};
BallCap ball_cap(double contact_radius_mm, double ball_radius_mm);

// The undeformed intersection of that ball with the gel (mm, H x W, >= 0),
// the circle centred at pixel (cx, cy) = (column, row).
std::vector<float> ball_indentation_mm(int H, int W, double mm_per_px, double cx, double cy, double contact_radius_px,
                                       double ball_radius_mm);

}  // namespace vtloc::sensor
