#include "engine/model/prepared_weights.h"

#include <algorithm>
#include <set>

#include "base/error.h"
#include "engine/model/batchnorm_fold.h"
#include "engine/model/gma.h"
#include "engine/ops/conv2d.h"
#include "engine/ops/point_common.h"

namespace vtloc {

namespace {

bool starts_with(const std::string& s, const std::string& p) { return s.compare(0, p.size(), p) == 0; }
bool ends_with(const std::string& s, const std::string& x) {
    return s.size() >= x.size() && s.compare(s.size() - x.size(), x.size(), x) == 0;
}

// The BatchNorm after a conv layer, by the file's naming (SPEC 7: torchvision's
// resnet18 and PointNet++'s module names), or "" for a layer without one.
std::string batchnorm_of(const std::string& layer) {
    const size_t dot = layer.rfind('.');
    const std::string parent = layer.substr(0, dot + 1), last = layer.substr(dot + 1);
    if (starts_with(layer, "tactile.backbone.")) {
        if (starts_with(last, "conv")) return parent + "bn" + last.substr(4);
        if (ends_with(layer, ".downsample.0")) return layer.substr(0, layer.size() - 1) + "1";
        return "";
    }
    if (starts_with(layer, "point.")) {
        for (const auto& [conv, bn] : {std::pair<std::string, std::string>{".conv_blocks.", ".bn_blocks."},
                                       {".mlp_convs.", ".mlp_bns."}}) {
            const size_t at = layer.find(conv);
            if (at != std::string::npos) return layer.substr(0, at) + bn + layer.substr(at + conv.size());
        }
    }
    return "";
}

}  // namespace

PreparedWeights prepare_weights(const ModelConfig& config, const WeightStore& file) {
    WeightStore work = file;  // fold_batchnorm adds its outputs beside the originals
    std::set<std::string> consumed;
    for (const std::string& name : file.names()) {
        if (!ends_with(name, ".weight")) continue;
        const std::string layer = name.substr(0, name.size() - 7);
        const std::string bn = batchnorm_of(layer);
        if (!bn.empty()) {
            const FoldedNames f = fold_batchnorm(work, layer, bn);
            HostTensor folded = work.get(f.weight);
            if (starts_with(layer, "tactile.")) {
                work.add(prepared::conv_ihwo(layer), ops::conv_weight_to_ihwo(folded));
            } else {
                work.add(prepared::point_kn(layer), ops::point_weight_kn(folded));
                folded.shape = {folded.shape[0], folded.size() / std::max<int64_t>(1, folded.shape[0])};
                work.add(prepared::point_2d(layer), std::move(folded));
            }
            consumed.insert({name, layer + ".bias", f.weight, bn + ".weight", bn + ".bias", bn + ".running_mean",
                             bn + ".running_var"});
        } else if (starts_with(layer, "tactile.mlp.")) {
            const HostTensor& lw = file.get(name);
            if (lw.shape.size() != 2) throw Error("weight '" + name + "' must be [out, in], got " + shape_str(lw.shape));
            work.add(prepared::head_ihwo(layer),
                     ops::conv_weight_to_ihwo(HostTensor(Shape{lw.shape[0], lw.shape[1], 1, 1}, lw.data)));
            consumed.insert(name);
        }
    }
    if (config.gma && file.has("gma.weight") &&
        split_weight_rows(work, "gma.weight", kPortableBindingBytes).size() > 1)
        consumed.insert("gma.weight");
    WeightStore out;
    out.set_config(file.config());
    for (const std::string& name : work.names())
        if (!consumed.count(name)) out.add(name, work.get(name));
    return PreparedWeights(std::move(out));
}

const HostTensor& prepared_tensor(const WeightStore& w, const std::string& name, const std::string& layer) {
    if (!w.has(name))
        throw Error("weight '" + layer + ".weight' is missing (or the weights were not prepared: prepare_weights)");
    return w.get(name);
}

}  // namespace vtloc
