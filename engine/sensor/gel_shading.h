#pragma once
// The gel's side of a touch: Taxim-style deformation of the pressed height
// field and the polynomial shading of the real sensor (the renderer's; the
// shape-from-frame of SPEC 9 inverts the shading).
#include <array>
#include <cstdint>
#include <vector>

#include "engine/sensor/calibration.h"

namespace vtloc::sensor {

// Gaussian blur widths (sigma, mm), applied in order; after each blur the
// contact region is restored (the gel never sinks below the undeformed
// intersection with the object), so the gel drapes smoothly from the contact
// edge outwards while the contact keeps the object's shape. Tuned against the
// 49 real frames (reality_check.h): mean |dRGB| inside the contacts 14.1
// (14.5 undeformed), outside 3.9 (5.0); narrower schedules miss the real
// halo, wider ones blur the contact edge.
inline const std::vector<double>& default_drape_sigmas_mm() {
    static const std::vector<double> s = {1.2, 0.8, 0.5, 0.3, 0.15};
    return s;
}

// In place on a rows x cols indentation map (mm, >= 0): the map as given is
// the undeformed intersection (the contact region where > 0).
void drape_gel(std::vector<float>& ind, int rows, int cols, double mm_per_px, const std::vector<double>& sigmas_mm);

// numpy.gradient of a height map (H x W) at (r, c): (d/drow, d/dcol), central
// differences inside, one-sided at the borders.
std::array<double, 2> height_gradient(const std::vector<float>& h, int H, int W, int r, int c);
// The table's (magnitude, direction) bin of a gradient (data/gelsight/README.md, step 3).
std::array<int, 2> table_bin(double g_row, double g_col, int bins);

// The polynomial table applied to a height map (pixels, H x W): writes
// H * W * 3 shading values (stored order) without the background.
class GelShader {
public:
    explicit GelShader(const Calibration& calib);
    void shade(const std::vector<float>& height_px, std::vector<float>& out) const;

private:
    int H_, W_, bins_;
    std::vector<double> poly_;  // [mag][dir][channel][6]
};

}  // namespace vtloc::sensor
