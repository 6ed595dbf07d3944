#include "engine/model/tactile_encoder.h"

#include <string>

#include "base/error.h"
#include "engine/model/prepared_weights.h"
#include "engine/ops/common.h"
#include "engine/ops/conv2d.h"
#include "engine/ops/tactile_preprocess.h"
#include "engine/ops/build.h"

namespace vtloc {

namespace {

// conv (+ its folded BatchNorm: prepare_weights) + optional residual + optional ReLU, torchvision names.
int conv_bn(Graph& g, const WeightStore& w, const std::string& conv, int x, int64_t stride, int64_t pad, bool relu,
            int residual = -1) {
    const std::string wname = prepared::conv_ihwo(conv), bname = prepared::bias(conv);
    const HostTensor& wt = prepared_tensor(w, wname, conv);
    ops::Conv2d c;
    c.stride_h = c.stride_w = stride;
    c.pad_h = c.pad_w = pad;
    c.layout = ops::kConvIHWO;
    c.act = relu ? ops::kActRelu : ops::kActNone;
    return ops::conv2d(g, x, g.weight(wname, wt.shape), g.weight(bname, {wt.shape[3]}), residual, c, conv);
}

}  // namespace

HostTensor tactile_image_input(const uint8_t* rgb, size_t bytes, int64_t height, int64_t width) {
    const int64_t lo = limits::kMinImageSide;
    if (height < lo || width < lo)
        throw Error("the tactile image is " + std::to_string(width) + "x" + std::to_string(height) +
                    "; the smallest accepted is " + std::to_string(lo) + "x" + std::to_string(lo));
    const size_t need = size_t(height) * size_t(width) * 3;
    if (bytes != need)
        throw Error("the tactile image holds " + std::to_string(bytes) + " bytes; " + std::to_string(width) + "x" +
                    std::to_string(height) + " RGB needs " + std::to_string(need));
    return ops::tactile_image_tensor(rgb, height, width);
}

int add_tactile_preprocess(Graph& g, const ModelConfig& config, int image) {
    const TactileConfig& c = config.tactile;
    return ops::tactile_preprocess(g, image, c.crop, c.in_size, "tactile.input");
}

int build_tactile_encoder(Graph& g, const WeightStore& w, const ModelConfig& config, int input) {
    const TactileConfig& c = config.tactile;
    const Shape& xs = g.value(input).shape;
    if (xs.size() != 4 || xs[1] != 3 || xs[2] != c.in_size || xs[3] != c.in_size)
        throw Error("tactile encoder input must be [N, 3, " + std::to_string(c.in_size) + ", " +
                    std::to_string(c.in_size) + "] (config in_size), got " + shape_str(xs));
    const std::string p = "tactile.backbone.";
    // Stem: conv 7x7/2 + BN + ReLU, max-pool 3x3/2 pad 1.
    int x = conv_bn(g, w, p + "conv1", input, 2, 3, true);
    x = ops::max_pool2d(g, x, ops::Pool2d{3, 3, 2, 2, 1, 1}, p + "maxpool");
    int64_t inplanes = c.widths[0];
    for (size_t s = 0; s < 4; ++s)
        for (int64_t b = 0; b < c.blocks[s]; ++b) {
            // torchvision BasicBlock: relu(bn2(conv2(relu(bn1(conv1(x))))) + skip); the
            // downsample (1x1 conv + BN) exists when the stride or the width changes.
            const std::string m = p + "layer" + std::to_string(s + 1) + "." + std::to_string(b) + ".";
            const int64_t stride = s > 0 && b == 0 ? 2 : 1;
            int skip = x;
            if (stride != 1 || inplanes != c.widths[s])
                skip = conv_bn(g, w, m + "downsample.0", x, stride, 0, false);
            int y = conv_bn(g, w, m + "conv1", x, stride, 1, true);
            x = conv_bn(g, w, m + "conv2", y, 1, 1, true, skip);
            inplanes = c.widths[s];
        }
    x = ops::global_avg_pool(g, x, p + "avgpool");  // [N, C, 1, 1]
    // The head's Linear layers run as 1x1 convolutions on the pooled [N, C, 1, 1]:
    // same arithmetic, and on CPU devices far faster than the shared-memory GEMM
    // of `linear` for one row (lavapipe: ~0.1 ms instead of ~11 ms).
    const int layers = int(c.mlp.size()) + 1;
    for (int i = 0; i < layers; ++i) {
        const std::string m = "tactile.mlp." + std::to_string(2 * i);
        // [in, 1, 1, out]: prepare_weights made it from a checked [out, in]
        const HostTensor& lw = prepared_tensor(w, prepared::head_ihwo(m), m);
        const int bias = w.has(m + ".bias") ? g.weight(m + ".bias", {lw.shape[3]}) : -1;
        ops::Conv2d head;
        head.layout = ops::kConvIHWO;
        head.act = i + 1 < layers ? ops::kActRelu : ops::kActNone;
        x = ops::conv2d(g, x, g.weight(prepared::head_ihwo(m), lw.shape), bias, -1, head, m);
    }
    return ops::flatten(g, x, "tactile.feature");
}

}  // namespace vtloc
