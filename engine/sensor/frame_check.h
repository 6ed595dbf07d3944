#pragma once
// Whether a tactile frame can show the gel at all, before anything is read from it.
#include <cstdint>
#include <string>
#include <vector>

namespace vtloc::sensor {

// Throws vtloc::Error("<what>: ...") for a frame (H x W x 3, either channel order) that is
// black (brightest value under 32: the lights off, the camera covered), over half white-clipped
// (every channel >= 250: over-exposed) or one flat colour. Not fitted knobs but wide margins: the
// 49 real presses, their empty frame, 300 of the benchmark's rendered touches and every shipped
// example have their brightest value at 205 or more, no clipped pixel and a spread of 27 or more.
void check_gel_frame(const std::vector<uint8_t>& pixels, const std::string& what);

}  // namespace vtloc::sensor
