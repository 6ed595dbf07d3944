#pragma once
// The heat-map colour map shared by the PLY writer and the PNG render.
#include <array>
#include <cstdint>

namespace vtloc::io {

// Maps t in [0, 1] (clamped; NaN as 0) to 8-bit RGB along a map of our own:
// dark navy -> indigo -> violet -> magenta -> coral -> orange -> pale yellow.
// Lightness rises monotonically, so the order reads in grey scale and for
// colour-blind readers, and the hot end stands out against a dark background.
std::array<uint8_t, 3> heat_color(float t);

}  // namespace vtloc::io
