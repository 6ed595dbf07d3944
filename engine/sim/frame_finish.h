#pragma once
// The renderer's last step: the shaded frame's appearance (gain, brightness,
// blur, noise), clipped and rounded to 8 bits. Internal to the renderer.
#include <cstdint>
#include <vector>

#include "engine/sim/touch_renderer.h"

namespace vtloc::sim::detail {

// shading + background -> gain, brightness, blur, noise, clip, round.
// `background` is H*W*3 (real_bg or the user's own).
std::vector<uint8_t> finish_frame(const std::vector<float>& shading, const std::vector<float>& background, int H,
                                  int W, const Appearance& look, uint64_t seed, bool noise);

}  // namespace vtloc::sim::detail
