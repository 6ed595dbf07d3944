// The GelSight calibration reader (engine/sensor/calibration.h) on arbitrary bytes:
// every input either loads as a calibration whose tables have the sizes its shapes
// promise (so the shading can index them unchecked) or throws vtloc::Error.
#include <cmath>
#include <cstdlib>
#include <vector>

#include "base/error.h"
#include "engine/sensor/calibration.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    try {
        const vtloc::sensor::Calibration c =
            vtloc::sensor::parse_calibration(std::vector<uint8_t>(data, data + size), "fuzz");
        const size_t H = size_t(c.height), W = size_t(c.width), B = size_t(c.bins), N = size_t(c.n_press);
        bool ok = c.real_bg.size() == H * W * 3 && c.depth_bg.size() == H * W && c.mm_per_px > 0;
        for (const auto& p : c.poly) ok = ok && p.size() == B * B * 6;
        ok = ok && c.press_imgs.size() == N * H * W * 3 && c.press_radius.size() == N && c.press_center.size() == N * 2;
        ok = ok && (N == 0 || c.press_f0.size() == H * W * 3);
        for (float v : c.real_bg) ok = ok && std::isfinite(v);
        for (int32_t r : c.press_radius) ok = ok && r > 0;
        if (!ok) std::abort();  // a calibration the shading would index out of bounds or with NaN
    } catch (const vtloc::Error&) {
    }
    return 0;
}
