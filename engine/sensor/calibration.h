#pragma once
// A real GelSight's optical calibration (Taxim-style polynomial table, real
// background, undeformed gel height) and its 49 real ball-press frames, read
// from the safetensors file described in data/gelsight/README.md.
#include <cstdint>
#include <string>
#include <vector>

namespace vtloc::sensor {

struct Calibration {
    int height = 120, width = 160;   // pixels
    double mm_per_px = 0.1245;
    int bins = 120;                  // polynomial table is bins x bins x 6 per channel
    // Channel c (0, 1, 2) in the frames' stored order (OpenCV BGR, so a frame
    // written with cv::imwrite is a correct-colour PNG).
    std::vector<float> poly[3];      // bins * bins * 6, index [mag_bin][dir_bin][k]
    std::vector<float> real_bg;      // height * width * 3 (stored order), added to the table's output
    std::vector<float> depth_bg;     // height * width, undeformed gel height in pixels
    // Real frames for the reality check (may be empty for a user's own sensor).
    std::vector<uint8_t> press_f0;   // height * width * 3
    std::vector<uint8_t> press_imgs; // n_press * height * width * 3
    std::vector<float> press_center; // n_press * 2 (x = column, y = row), pixels
    std::vector<int32_t> press_radius;  // n_press, pixels
    int n_press = 0;
};

// Throws vtloc::Error naming the file and the tensor for a missing tensor,
// a wrong shape or dtype, or a non-finite value.
Calibration load_calibration(const std::string& path);
// The same from a file's bytes (`source` names it in errors; the fuzz target).
Calibration parse_calibration(std::vector<uint8_t> bytes, const std::string& source);

// The shipped calibration: $VTLOC_GELSIGHT_CALIB if set, else
// <source tree>/data/gelsight/objectfolder_gelsight_calib.safetensors, else an
// install's share/vtloc/data/gelsight/. Throws vtloc::Error when none exists.
std::string default_calibration_path();

}  // namespace vtloc::sensor
