#pragma once
// Shared by the renderer and sensor tests.
#include "engine/sensor/calibration.h"
#include "engine/sim/touch_renderer.h"

namespace vtloc::test {

// The shipped calibration, read once per test process.
inline const sim::Calibration& calib() {
    static const sim::Calibration c = sim::load_calibration(sim::default_calibration_path());
    return c;
}

// Noise off: frames comparable pixel for pixel.
inline sim::Appearance no_noise() {
    sim::Appearance a;
    a.noise_sigma = 0;
    return a;
}

}  // namespace vtloc::test
