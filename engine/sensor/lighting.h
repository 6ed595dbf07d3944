#pragma once
// A frame's lighting matched to the sensor's empty frame before the gel's shape is
// read (SPEC 9). LEDs drift and cameras re-expose, and our renderer's training
// frames vary brightness and per-channel gain: frame = gain (empty + shading) +
// offset. The calibration reads shading, so a gain or offset the empty frame lacks
// reads as slopes everywhere. Where the gel is flat (outside the contact, and on
// a flat pressed face) the shading is zero, so a least-squares fit of frame against
// empty per channel, over the pixels it explains best, recovers gain and offset.
#include <cstdint>
#include <vector>

namespace vtloc::sensor {

struct LightingFit {
    double gain[3] = {1, 1, 1}, offset[3] = {0, 0, 0};  // frame ~ gain * empty + offset, per stored channel
};

// frame, empty: H x W x 3 (the same stored order). Fits on the `keep` share of
// pixels with the smallest residuals (trimmed least squares, a few rounds from all
// pixels); a gain outside [0.5, 2] or a channel too flat to separate gain from offset
// (empty's standard deviation below 2 grey levels) keeps gain 1 and fits the offset alone.
LightingFit fit_lighting(const std::vector<uint8_t>& frame, const std::vector<uint8_t>& empty, double keep = 0.5);

// The frame with the fit's gain and offset undone (rounded, clamped to 0..255).
std::vector<uint8_t> match_lighting(const std::vector<uint8_t>& frame, const std::vector<uint8_t>& empty, LightingFit* fit = nullptr);

}  // namespace vtloc::sensor
