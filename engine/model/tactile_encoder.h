#pragma once
// The tactile branch of SPEC section 2: preprocessing and the ResNet-18-topology
// encoder with its MLP head, giving F^t. Every number comes from the config
// ("tactile": crop, in_size, widths, blocks, mlp; and "C").
#include "engine/graph.h"
#include "engine/model/model_config.h"
#include "engine/weights.h"

namespace vtloc {

// image: I32 [H, W, 3] graph input holding byte values (ops::tactile_image_tensor).
// Returns `tactile.input`, [1, 3, S, S].
// A uint8 RGB frame (row-major H x W x 3, `bytes` long) as the graph's
// tactile.image input; throws naming the size when a side is below
// limits::kMinImageSide or the byte count does not match.
HostTensor tactile_image_input(const uint8_t* rgb, size_t bytes, int64_t height, int64_t width);

int add_tactile_preprocess(Graph& g, const ModelConfig& config, int image);

// input: [N, 3, S, S] preprocessed images. Returns F^t, [N, C] (node
// `tactile.feature`). Weights are read under torchvision's resnet18 names with
// prefix `tactile.backbone.` and the head's `tactile.mlp.{0,2,..}` (Linear [out,
// in]), as prepare_weights left them: each BatchNorm folded into its convolution
// (`<conv>.weight#bn#ihwo` / `<conv>.bias#bn`, conv2d's IHWO layout) and the
// head's Linear weights as `tactile.mlp.<i>.weight#ihwo`, run as 1x1 convolutions.
int build_tactile_encoder(Graph& g, const WeightStore& w, const ModelConfig& config, int input);

}  // namespace vtloc
