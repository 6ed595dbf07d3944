#pragma once
// The weights graphs read, made once per model from its file's tensors: every
// BatchNorm folded into the convolution before it, each folded weight in the
// layouts the GPU reads (tactile: IHWO; point MLPs: [out, in] and input-major
// [in, out]), the tactile head's Linear layers as 1x1 IHWO convolutions, and
// W^d split into row chunks that fit any device's binding limit. The graph
// builders only read this store (const) by the names below; the file's
// tensors that only fed the folding are not kept.
#include <string>
#include <utility>

#include "engine/model/model_config.h"
#include "engine/weights.h"

namespace vtloc {

class PreparedWeights;

// Throws naming the layer when a convolution's BatchNorm or a statistic is missing.
PreparedWeights prepare_weights(const ModelConfig& config, const WeightStore& file);

// What prepare_weights made, and only that (nothing else constructs one), so a
// holder can take it without preparing again; read-only once made.
class PreparedWeights {
public:
    const WeightStore& store() const { return store_; }
    operator const WeightStore&() const { return store_; }  // what the builders and executors read

private:
    explicit PreparedWeights(WeightStore s) : store_(std::move(s)) {}
    friend PreparedWeights prepare_weights(const ModelConfig& config, const WeightStore& file);
    WeightStore store_;
};

// Names of the prepared tensors of a conv (+ BN) layer and of a tactile head layer.
namespace prepared {
inline std::string bias(const std::string& conv) { return conv + ".bias#bn"; }
inline std::string conv_ihwo(const std::string& conv) { return conv + ".weight#bn#ihwo"; }
inline std::string point_2d(const std::string& conv) { return conv + ".weight#bn#2d"; }
inline std::string point_kn(const std::string& conv) { return conv + ".weight#bn#kn"; }
inline std::string head_ihwo(const std::string& linear) { return linear + ".weight#ihwo"; }
}  // namespace prepared

// A prepared tensor; a missing one is named as the file's layer it comes from.
const HostTensor& prepared_tensor(const WeightStore& w, const std::string& name, const std::string& layer);

}  // namespace vtloc
