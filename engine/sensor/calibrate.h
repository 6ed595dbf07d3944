#pragma once
// A sensor calibration of the user's own (`vtloc calibrate`, SPEC 9): from
// frames of a ball of known size pressed into the gel and the sensor's empty
// frame, a Taxim-style table in the shipped format (data/gelsight/README.md):
// per (slope magnitude, direction) bin and channel, a quadratic in the pixel
// position predicting the colour change. docs/calibrate.md gives the method
// and how well it explains held-out real presses.
#include <string>
#include <vector>

#include "engine/sensor/calibration.h"

namespace vtloc::sensor {

struct BallPress {
    std::vector<uint8_t> frame;  // H x W x 3, the calibration's stored channel order
    double cx = 0, cy = 0;       // the contact circle's centre (column, row), pixels
    double radius_px = 0;        // and radius
};

struct CalibrateOptions {
    double ball_radius_mm = 2.0;
    double mm_per_px = 0.1245;
    int bins = 120;
    // A bin's samples are pooled from the bins around it, the square widened
    // until it holds min_samples; the position terms are shrunk by `ridge`
    // (in samples' worth) so a pool from one place cannot tilt the table
    // elsewhere. These three fitted on the even presses' own halves (docs/calibrate.md).
    int min_samples = 128;
    double ridge = 1.0;
    double background_sigma_px = 3.0;  // the empty frame smoothed into real_bg (its noise)
    int flat_stride = 3;               // pixels far from the contact: every n-th row and column
    bool drape = true;                 // the renderer's gel drape around the contact
};

// The gel's height (pixels, H x W) the press makes, as the renderer would
// press it (draped unless o.drape is false): the fit's and the check's model.
std::vector<float> press_height_px(const BallPress& p, int H, int W, const CalibrateOptions& o);

// Throws vtloc::Error naming the press for a wrong frame size, a circle off
// the frame or a non-positive radius, and for no presses at all.
Calibration fit_calibration(const std::vector<BallPress>& presses, const std::vector<uint8_t>& empty, int H, int W,
                            const CalibrateOptions& o = {});

// How well a calibration explains a press: the press rendered with its table
// (+ real_bg, over depth_bg) against the real frame, mean |dRGB| per channel
// inside the contact circle and outside it.
struct PressResidual {
    double inside = 0, outside = 0;
};
PressResidual press_residual(const Calibration& c, const BallPress& p, const CalibrateOptions& o = {});

// The circle (centre, radius) that the calibration explains best for this
// press's frame: coordinate descent on the whole frame's mean |dRGB| from the
// press's circle, steps of 2, 1 and 0.5 px. `vtloc calibrate` starts from the
// detected contacts (detect_contact: the colour change, whose halo and shadow
// make it too wide and off-centre) and alternates fitting and refining.
BallPress refine_circle(const Calibration& c, BallPress p, const CalibrateOptions& o = {});

// The press with the contact detect_contact finds in its frame as its circle;
// throws vtloc::Error naming the press (`name`) when the frame shows none.
BallPress detected_circle(BallPress p, const std::vector<uint8_t>& empty, int H, int W, const std::string& name);

// The whole fit: presses whose radius_px is 0 get the detected contact, then
// fitting and refining (only those) alternate until their circles move less
// than 0.25 px at the median or after max_rounds refinements. Presses with
// circles of their own keep them.
struct CalibrateRun {
    Calibration calib;
    std::vector<BallPress> presses;  // with the circles the table was fitted with
    int rounds = 0;
    double last_move_px = 0;         // median circle move of the last round
};
CalibrateRun calibrate(std::vector<BallPress> presses, const std::vector<uint8_t>& empty, int H, int W,
                       const CalibrateOptions& o = {}, int max_rounds = 8);

// The shipped file's layout; the presses (if any) go in as press_* tensors.
void save_calibration(const std::string& path, const Calibration& c);

// The calibration's own presses with their annotated circles.
std::vector<BallPress> calibration_presses(const Calibration& c);

}  // namespace vtloc::sensor
