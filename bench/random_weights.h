#pragma once
// Random weights of a config's shapes for benches run without a weight file:
// timing does not depend on the values, only on the shapes, but BatchNorm
// statistics are perturbed so folding does real work.
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "engine/weights.h"

namespace vtloc::bench {

// The paper config (weights_tools' vtloc-r18), for the branch benches' random weights.
extern const char* const kR18Config;

class RandomWeights {
public:
    RandomWeights(WeightStore& w, uint32_t seed) : w_(w), rng_(seed) {}

    void normal(const std::string& name, const Shape& s, double stddev, double mean = 0.0);
    // A convolution (He-initialised; `bias` adds conv.bias) and the eval-mode
    // BatchNorm after it. weight_shape is [out, in, kh, kw].
    void conv_bn(const std::string& conv, const std::string& bn, const Shape& weight_shape, bool bias);
    // nn.Sequential(Linear, ReLU, ..., Linear) named prefix.0, prefix.2, ... over `sizes`.
    void mlp(const std::string& prefix, const std::vector<int64_t>& sizes);

private:
    WeightStore& w_;
    std::mt19937 rng_;
};

// Random weights of the point encoder of `config` (a model config as JSON): each set
// abstraction's conv + BatchNorm layers, the group-all layers and the head MLP.
WeightStore random_point_weights(const nlohmann::json& config, uint32_t seed);

}  // namespace vtloc::bench
