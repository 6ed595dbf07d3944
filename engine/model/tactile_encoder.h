#pragma once
// The tactile branch of SPEC section 2: preprocessing and the ResNet-18-topology
// encoder with its MLP head, giving F^t. Every number comes from the config
// (weight file metadata "tactile": crop, in_size, widths, blocks, mlp; and "C").
#include <nlohmann/json.hpp>
#include <vector>

#include "engine/graph.h"
#include "engine/weights.h"

namespace vtloc {

struct TactileConfig {
    int64_t crop = 0, in_size = 0, C = 0;
    std::vector<int64_t> widths, blocks, mlp;  // 4 stage widths, 4 block counts, head hidden sizes
};

// Validates config["tactile"] and config["C"] (the weights_tools schema); throws
// vtloc::Error naming the offending key.
TactileConfig tactile_config(const nlohmann::json& config);

// image: I32 [H, W, 3] graph input holding byte values (ops::tactile_image_tensor).
// Returns `tactile.input`, [1, 3, S, S].
int add_tactile_preprocess(Graph& g, const nlohmann::json& config, int image);

// input: [N, 3, S, S] preprocessed images. Returns F^t, [N, C] (node
// `tactile.feature`). Weights are read under torchvision's resnet18 names with
// prefix `tactile.backbone.` and the head's `tactile.mlp.{0,2,..}` (Linear [out,
// in]). Each BatchNorm is folded into its convolution here, and the folded
// weights are added to `w` as `<conv>.weight#bn#ihwo` / `<conv>.bias#bn` in
// conv2d's IHWO layout (the originals stay); the head's Linear weights likewise as
// `tactile.mlp.<i>.weight#ihwo`, run as 1x1 convolutions.
int build_tactile_encoder(Graph& g, WeightStore& w, const nlohmann::json& config, int input);

}  // namespace vtloc
