#pragma once
// The tactile_preprocess op's input format and its crop rule.
#include <cstdint>

#include "engine/tensor.h"

namespace vtloc::ops {

// The smallest image side the op accepts: anything smaller is not a sensor frame.
inline constexpr int64_t kMinTactileSide = 8;

// A uint8 RGB image (row-major H x W x 3) as the op's input: an I32 [H, W, 3]
// tensor holding one byte value per element. Why not packed bytes: core Vulkan
// 1.1 has no 8-bit storage (VK_KHR_8bit_storage is optional and the engine needs
// no device extension), every graph value is 32-bit, and this way the value's
// shape is the image's own, so the executor checks H, W and 3 like any input;
// the 4x upload (3.7 MB for 640 x 480) is small next to the encoder (lavapipe:
// ~1.5 ms for such a frame's preprocessing, upload included). Sizes are checked
// where the image meets the graph (tactile_preprocess needs >= 8 x 8).
HostTensor tactile_image_tensor(const uint8_t* rgb, int64_t height, int64_t width);

// First source row/column of torchvision's CenterCrop along one axis: negative
// (zero padding) when size < crop, else round((size - crop) / 2) with half to even.
int64_t center_crop_start(int64_t size, int64_t crop);

}  // namespace vtloc::ops
