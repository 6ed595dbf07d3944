#include "engine/sensor/frame_check.h"

#include <algorithm>

#include "base/error.h"

namespace vtloc::sensor {

void check_gel_frame(const std::vector<uint8_t>& pixels, const std::string& what) {
    if (pixels.size() < 3) throw Error(what + ": an empty frame");
    const auto [lo, hi] = std::minmax_element(pixels.begin(), pixels.end());
    size_t white = 0;
    for (size_t i = 0; i + 2 < pixels.size(); i += 3) white += pixels[i] >= 250 && pixels[i + 1] >= 250 && pixels[i + 2] >= 250;
    const size_t n = pixels.size() / 3;
    if (*hi < 32)
        throw Error(what + ": the frame is black (its brightest value is " + std::to_string(*hi) +
                    " of 255): the sensor's lights off or its camera covered?");
    if (2 * white > n)
        throw Error(what + ": " + std::to_string(100 * white / n) + " % of the frame is white (every channel >= 250): over-exposed, it cannot show the gel");
    if (*hi - *lo <= 2)
        throw Error(what + ": the frame is one flat colour (values " + std::to_string(*lo) + ".." + std::to_string(*hi) + "): no image of the gel");
}

}  // namespace vtloc::sensor
