#pragma once
// The gel's shape from one frame (SPEC 9), the CPU reference: the colour change
// against the sensor's empty frame, inverted through the calibration into the
// gel surface's gradient (per-tile lookup tables), a contact mask from the
// indentation's gradient, and a Poisson solve inside the mask for the
// indentation. The gradient, the mask and the solve are ops gel_gradient,
// gel_contact_mask and masked_poisson's CPU references (engine/ops/gel_ops.h,
// engine/ops/gel_mask.h). docs/gel_shape.md gives the method, its constants and what the
// 49 real ball presses say of it.
#include <array>
#include <cstdint>
#include <vector>

#include "engine/sensor/calibration.h"

namespace vtloc::sensor {

// The calibration's shading inverted: for each of tiles_y x tiles_x image tiles,
// an n^3 table over the colour change (each channel in [-256, 256), cells of
// 512 / n) holding the gel's gradient (g_row, g_col) whose predicted colour
// change falls there, averaged as surface normals over the tile's pixels on a
// `step`-pixel grid and every (magnitude, direction) bin but the last; empty
// cells take the mean of their filled neighbours, repeatedly. Tiles (and the linear inverse's
// rows) on up to `threads` host threads (0: up to 4); the same bits on any number.
struct GradientLut {
    int n = 64, tiles_y = 3, tiles_x = 4, height = 0, width = 0;
    std::vector<float> table;   // [tiles_y][tiles_x][n][n][n][2]
    std::vector<float> linear;  // [H][W][6]: build_linear_inverse, for gentle slopes
};
struct LutGrid {
    int n = 64, tiles_y = 3, tiles_x = 4, step = 4;
};
GradientLut build_gradient_lut(const Calibration& c, int threads = 0, const LutGrid& grid = {});

// The mask threshold for frames rendered by vtloc synth's renderer, whose presses (a large object,
// 0.3-1.5 mm) are gentle: chosen on renders of the procedural solids (docs/gel_shape.md). The
// default 0.7 is the real sensor's, from its ball presses, whose non-local halo the renderer lacks.
inline constexpr double kRenderedMaskThreshold = 0.05;

struct ShapeOptions {
    double mask_threshold = 0.7;  // on the 3x3 mean of the indentation's gradient magnitude
    // Where the tables' slope is at most this, the linearised inverse (gel_linear_inverse.h)
    // gives the gradient; 0: the tables everywhere. Fitted on renders of the procedural solids.
    double gentle_slope = 0.35;
    int open_radius = 2, close_radius = 2;  // the mask's opening and closing (discs, pixels)
    // The Poisson solve (ops::gel::masked_poisson_multilevel): red-black SOR, sor_iterations
    // sweeps on the full grid, from a coarse start where sor_levels > 0: the grid halved up to
    // sor_levels times, sor_coarse_iterations sweeps on each coarse grid (0: from zeros). From
    // zeros, 50 sweeps converge on a real press's small mask, not on a rendered frame's wide one.
    int sor_iterations = 50;
    int sor_levels = 0, sor_coarse_iterations = 0;
    double sor_omega = 1.85;
};

// For frames rendered by vtloc synth's renderer: kRenderedMaskThreshold, and the solve from a
// coarse start (2 halvings, 30 sweeps on each, 10 on the frame's grid), as 50 sweeps from zeros
// stop well short on their wide masks (docs/gel_shape.md, "A coarse start").
inline ShapeOptions rendered_frame_options() {
    ShapeOptions o;
    o.mask_threshold = kRenderedMaskThreshold;
    o.sor_levels = 2, o.sor_coarse_iterations = 30, o.sor_iterations = 10;
    return o;
}

struct GelShape {
    int height = 0, width = 0;
    std::vector<float> grad_row, grad_col;  // the indentation's gradient (mm per mm), H x W
    std::vector<float> depth_mm;            // the indentation, >= 0 in the contact, 0 outside it
    std::vector<uint8_t> mask;              // the contact (0/1)
};

// The contact (0/1, H x W) from the indentation's gradient [H, W, 2] (row, col): op
// gel_contact_mask's reference (a radius <= 0: no closing / opening).
std::vector<uint8_t> contact_mask(const std::vector<float>& grad, int H, int W, const ShapeOptions& o = {});

// frame, empty: H x W x 3 in the calibration's stored channel order (its size).
// Throws vtloc::Error for frames of another size.
GelShape gel_shape(const Calibration& c, const GradientLut& lut, const std::vector<uint8_t>& frame,
                   const std::vector<uint8_t>& empty, const ShapeOptions& o = {});

// The least-squares sphere through points (x, y, z triples): centre and radius.
struct Sphere {
    std::array<double, 3> centre{};
    double radius = 0;
};
Sphere fit_sphere(const std::vector<double>& xyz);

}  // namespace vtloc::sensor
