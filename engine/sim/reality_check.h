#pragma once
// How close the simulated touches are to the real sensor: each of the
// calibration's 49 real ball-press frames is rendered (a ball pressed so that
// its contact circle has the annotated radius at the annotated centre) and
// both frames go through one image-based contact detector.
#include <string>
#include <vector>

#include "engine/sensor/ball_press.h"
#include "engine/sensor/calibration.h"

namespace vtloc::sim {

// The sensor model lives in engine/sensor; the simulator names it as before.
using sensor::Calibration;
using sensor::default_calibration_path;
using sensor::load_calibration;

// The image-based contact detector lives with the sensor model.
using sensor::DetectedContact;
using sensor::detect_contact;
using sensor::kContactFraction;

struct RealityFrame {
    int index = 0;
    double annotated_cx = 0, annotated_cy = 0, annotated_r = 0;  // from the calibration file
    double press_mm = 0, ball_radius_mm = 0;
    DetectedContact real, sim;
    double radius_ratio = 0;    // sim.radius / real.radius
    double centre_dist = 0;     // |sim centre - real centre|, pixels
    double drgb_inside = 0;     // mean |rendered - real| over channels and pixels inside the annotated circle
    double drgb_outside = 0;    // ... and outside it
};

struct RealityReport {
    std::vector<RealityFrame> frames;
    double median_radius_err = 0, max_radius_err = 0;  // |ratio - 1|
    double median_centre_dist = 0, max_centre_dist = 0;
    double mean_drgb_inside = 0, mean_drgb_outside = 0;  // means over the frames
    double max_drgb_inside = 0, max_drgb_outside = 0;
    // What no renderer fed only the annotations can beat: the offsets (real -
    // rendered centre) minus their best in-sample fit by a quadratic in the
    // annotated centre (x, y, x^2, y^2, xy, 1; least squares per axis). A
    // render error that varies smoothly with where the ball pressed is
    // absorbed by that fit; what is left is scatter between real frames that
    // the annotations do not carry.
    double floor_median_centre_dist = 0, floor_max_centre_dist = 0;
    int floor_frames_over_3px = 0;
};

struct RealityOptions {
    double ball_radius_mm = 2.0;  // the real presses used a 4 mm diameter ball
    int sphere_subdivisions = 5;  // 20480 triangles: faceting well below a pixel
    std::vector<double> drape_sigmas_mm;  // empty: the renderer's default
    // Side by side: rows of real | rendered | |difference| x diff_gain for
    // these frames (indices out of range are skipped).
    std::string png_path;         // empty: no picture
    std::vector<int> png_frames = {0, 1, 2, 3, 5, 6, 24, 48};
    double diff_gain = 4;
};

// With the default drape, over the 49 frames: |radius ratio - 1| median 0.039,
// max 0.123; centre distance median 3.1 px, max 7.2 px: the 3 px every-frame
// goal is not met, because the real halo loses far more blue light towards
// the upper right than the local polynomial shading can produce (a non-local
// optical effect; what was ruled out is in tests/test_sim_reality.cpp); mean |dRGB| 14.1 inside the
// annotated circles (14.5 undeformed), 3.9 outside (5.0 undeformed). The
// floor above is median 1.4 px, max 3.6 px (1 frame over 3 px): even a
// renderer whose centre error were a perfect quadratic field, fitted to these
// very frames, would miss the every-frame goal.
//
// Renders without noise: the real frames carry their own, and independent
// noise on the rendered side would only add to |dRGB| (by ~sigma * 1.13).
// Throws vtloc::Error when the calibration has no press frames or the PNG
// cannot be written (naming the path).
RealityReport reality_check(const Calibration& calib, const RealityOptions& options = {});

}  // namespace vtloc::sim
