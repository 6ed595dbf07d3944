#pragma once
// Point Filtering: a model-free baseline in the spirit of the ObjectFolder
// benchmark's. For every candidate contact of an object, render with the
// GelSight simulator the touch the sensor would see there (several spins
// about the sensor axis, fixed press, no noise), and rank the candidates by
// how much their rendered frame looks like the observed one.
//
// Image distance (docs/eval.md, docs/usage.md "Synthetic benchmark"): both frames minus
// their empty-sensor background, averaged over the three channels into one
// signed float image, blurred (Gaussian, blur_sigma_px), then
// d = 1 - NCC(observed, rendered) (zero-mean normalised cross-correlation over
// the whole frame; d = 1 when either image is flat). A candidate's distance is
// the smallest over its spins; candidates with no valid render rank last.
#include <cstdint>
#include <optional>
#include <vector>

#include "engine/io/mesh.h"
#include "engine/sensor/calibration.h"
#include "engine/sim/metrics.h"

namespace vtloc::sim {

// The sensor model lives in engine/sensor; the simulator names it as before.
using sensor::Calibration;
using sensor::default_calibration_path;
using sensor::load_calibration;

struct PointFilterOptions {
    int spins = 8;              // spins 0, 360/spins, ... degrees
    double press_mm = 0.9;      // mid-range of the datasets' 0.3 .. 1.5 mm
    double blur_sigma_px = 1.0;
};

// An 8-bit 3-channel frame, row-major (channel order does not matter: the
// distance averages the channels).
struct Frame8 {
    int height = 0, width = 0;
    std::vector<uint8_t> data;
};

class PointFilter {
public:
    // Renders every candidate at construction (the renders do not depend on
    // the touch, so one PointFilter per object serves all its touches).
    // normals: the outward unit surface normals at the candidates.
    // background: the observed frames' empty-sensor frame (e.g. the dataset's
    // background.png); none = the simulator's own undeformed frame.
    PointFilter(const Calibration& calib, const io::TriangleMesh& mesh, std::optional<double> mm_per_px,
                const std::vector<Point3>& candidates, const std::vector<Point3>& normals,
                std::optional<Frame8> background, const PointFilterOptions& options = {});

    // Distance of every candidate to the observed frame (resized to the
    // simulator's size when it differs; so is the background).
    std::vector<double> distances(const Frame8& observed) const;
    // Candidates by ascending distance (ties to the lower index).
    std::vector<int> ranking(const Frame8& observed) const;
    // Candidates that had no valid render at any spin.
    int unrenderable() const { return unrenderable_; }

private:
    std::vector<float> prepare(const Frame8& frame, const std::vector<float>& background) const;

    int height_ = 0, width_ = 0;
    PointFilterOptions options_;
    std::vector<float> observed_bg_;                      // height * width * 3, float
    std::vector<std::vector<std::vector<float>>> renders_;  // [candidate][spin] prepared images
    int unrenderable_ = 0;
};

}  // namespace vtloc::sim
