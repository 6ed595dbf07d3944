#include "engine/model/tactile_encoder.h"

#include <string>

#include "engine/error.h"
#include "engine/model/batchnorm_fold.h"
#include "engine/ops/common.h"
#include "engine/ops/conv2d.h"

namespace vtloc {

namespace {

int64_t pos_int(const nlohmann::json& j, const std::string& where) {
    if (!j.is_number_integer() || j.get<int64_t>() <= 0) throw Error("config " + where + ": expected a positive integer");
    return j.get<int64_t>();
}

std::vector<int64_t> pos_ints(const nlohmann::json& j, const std::string& where, size_t min_len, size_t max_len) {
    if (!j.is_array() || j.size() < min_len || j.size() > max_len)
        throw Error("config " + where + ": expected a list of " +
                    (min_len == max_len ? std::to_string(min_len) : ">= " + std::to_string(min_len)) +
                    " positive integers");
    std::vector<int64_t> out;
    for (size_t i = 0; i < j.size(); ++i) out.push_back(pos_int(j[i], where + "[" + std::to_string(i) + "]"));
    return out;
}

// conv (+ folded BatchNorm) + optional residual + optional ReLU, torchvision names.
int conv_bn(Graph& g, WeightStore& w, const std::string& conv, const std::string& bn, int x, int64_t stride,
            int64_t pad, bool relu, int residual = -1) {
    const std::string wname = conv + ".weight#bn#ihwo", bname = conv + ".bias#bn";
    if (!w.has(wname) || !w.has(bname)) {  // a second touch in the same graph reuses them
        FoldedNames f = fold_batchnorm(w, conv, bn);
        w.add(wname, ops::conv_weight_to_ihwo(w.get(f.weight)));
        if (f.bias != bname) throw Error("unexpected folded bias name '" + f.bias + "'");
    }
    const HostTensor& wt = w.get(wname);
    std::vector<int> in{x, g.weight(wname, wt.shape), g.weight(bname, {wt.shape[3]})};
    if (residual >= 0) in.push_back(residual);
    Params p{{"stride", double(stride)}, {"pad", double(pad)}, {"weight_layout", double(ops::kConvIHWO)},
             {"act", double(relu ? ops::kActRelu : ops::kActNone)}, {"residual", residual >= 0 ? 1.0 : 0.0}};
    return g.add1("conv2d", in, p, conv);
}

}  // namespace

TactileConfig tactile_config(const nlohmann::json& config) {
    if (!config.is_object() || !config.contains("tactile") || !config["tactile"].is_object())
        throw Error("config: missing the \"tactile\" object");
    if (!config.contains("C")) throw Error("config: missing \"C\"");
    const nlohmann::json& t = config["tactile"];
    for (const char* k : {"crop", "in_size", "widths", "blocks", "mlp"})
        if (!t.contains(k)) throw Error(std::string("config tactile: missing \"") + k + "\"");
    TactileConfig c;
    c.crop = pos_int(t["crop"], "tactile.crop");
    c.in_size = pos_int(t["in_size"], "tactile.in_size");
    c.widths = pos_ints(t["widths"], "tactile.widths", 4, 4);
    c.blocks = pos_ints(t["blocks"], "tactile.blocks", 4, 4);
    c.mlp = pos_ints(t["mlp"], "tactile.mlp", 0, 64);
    c.C = pos_int(config["C"], "C");
    return c;
}

int add_tactile_preprocess(Graph& g, const nlohmann::json& config, int image) {
    TactileConfig c = tactile_config(config);
    return g.add1("tactile_preprocess", {image}, {{"crop", double(c.crop)}, {"size", double(c.in_size)}},
                  "tactile.input");
}

int build_tactile_encoder(Graph& g, WeightStore& w, const nlohmann::json& config, int input) {
    TactileConfig c = tactile_config(config);
    const Shape& xs = g.value(input).shape;
    if (xs.size() != 4 || xs[1] != 3 || xs[2] != c.in_size || xs[3] != c.in_size)
        throw Error("tactile encoder input must be [N, 3, " + std::to_string(c.in_size) + ", " +
                    std::to_string(c.in_size) + "] (config in_size), got " + shape_str(xs));
    const std::string p = "tactile.backbone.";
    // Stem: conv 7x7/2 + BN + ReLU, max-pool 3x3/2 pad 1.
    int x = conv_bn(g, w, p + "conv1", p + "bn1", input, 2, 3, true);
    x = g.add1("max_pool2d", {x}, {{"kernel", 3}, {"stride", 2}, {"pad", 1}}, p + "maxpool");
    int64_t inplanes = c.widths[0];
    for (size_t s = 0; s < 4; ++s)
        for (int64_t b = 0; b < c.blocks[s]; ++b) {
            // torchvision BasicBlock: relu(bn2(conv2(relu(bn1(conv1(x))))) + skip); the
            // downsample (1x1 conv + BN) exists when the stride or the width changes.
            const std::string m = p + "layer" + std::to_string(s + 1) + "." + std::to_string(b) + ".";
            const int64_t stride = s > 0 && b == 0 ? 2 : 1;
            int skip = x;
            if (stride != 1 || inplanes != c.widths[s])
                skip = conv_bn(g, w, m + "downsample.0", m + "downsample.1", x, stride, 0, false);
            int y = conv_bn(g, w, m + "conv1", m + "bn1", x, stride, 1, true);
            x = conv_bn(g, w, m + "conv2", m + "bn2", y, 1, 1, true, skip);
            inplanes = c.widths[s];
        }
    x = g.add1("global_avg_pool", {x}, {}, p + "avgpool");  // [N, C, 1, 1]
    // The head's Linear layers run as 1x1 convolutions on the pooled [N, C, 1, 1]:
    // same arithmetic, and on CPU devices far faster than the shared-memory GEMM
    // of `linear` for one row (lavapipe: ~0.1 ms instead of ~11 ms).
    const int layers = int(c.mlp.size()) + 1;
    for (int i = 0; i < layers; ++i) {
        const std::string m = "tactile.mlp." + std::to_string(2 * i);
        const HostTensor& lw = w.get(m + ".weight");
        if (lw.shape.size() != 2) throw Error("weight '" + m + ".weight' must be [out, in], got " + shape_str(lw.shape));
        if (!w.has(m + ".weight#ihwo"))
            w.add(m + ".weight#ihwo", ops::conv_weight_to_ihwo(HostTensor(Shape{lw.shape[0], lw.shape[1], 1, 1}, lw.data)));
        std::vector<int> in{x, g.weight(m + ".weight#ihwo", {lw.shape[1], 1, 1, lw.shape[0]})};
        if (w.has(m + ".bias")) in.push_back(g.weight(m + ".bias", {lw.shape[0]}));
        const bool relu = i + 1 < layers;
        x = g.add1("conv2d", in,
                   {{"weight_layout", double(ops::kConvIHWO)}, {"act", double(relu ? ops::kActRelu : ops::kActNone)}}, m);
    }
    return g.add1("flatten", {x}, {}, "tactile.feature");
}

}  // namespace vtloc
