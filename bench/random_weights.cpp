#include "bench/random_weights.h"

#include <cmath>

namespace vtloc::bench {

const char* const kR18Config = R"({"name": "vtloc-r18", "C": 128, "K": 5,
  "tactile": {"crop": 320, "in_size": 224, "widths": [64, 128, 256, 512], "blocks": [2, 2, 2, 2], "mlp": [256]},
  "point": {"n_points": 1024, "use_normals": true,
    "sa": [{"npoint": 512, "radii": [0.1, 0.2, 0.4], "nsample": [16, 32, 128], "mlps": [[32, 32, 64], [64, 64, 128], [64, 96, 128]]},
           {"npoint": 128, "radii": [0.2, 0.4, 0.8], "nsample": [32, 64, 128], "mlps": [[64, 64, 128], [128, 128, 256], [128, 128, 256]]}],
    "group_all_mlp": [256, 512, 1024], "mlp": [512]},
  "gma": {"n_points": 1024, "channels": 64, "decoder": [64, 32, 16]},
  "ilu": {"iters": 16, "head_hidden": 64}, "head": "ilu", "mcr": null})";

void RandomWeights::normal(const std::string& name, const Shape& s, double stddev, double mean) {
    std::normal_distribution<float> d{float(mean), float(stddev)};
    HostTensor t(s);
    for (float& v : t.data) v = d(rng_);
    w_.add(name, std::move(t));
}

void RandomWeights::conv_bn(const std::string& conv, const std::string& bn, const Shape& weight_shape, bool bias) {
    const int64_t out = weight_shape.at(0);
    normal(conv + ".weight", weight_shape, std::sqrt(2.0 / double(numel(weight_shape) / out)));
    if (bias) normal(conv + ".bias", {out}, 0.1);
    normal(bn + ".weight", {out}, 0.1, 1.0);
    normal(bn + ".bias", {out}, 0.1);
    normal(bn + ".running_mean", {out}, 0.1);
    std::uniform_real_distribution<float> var(0.5f, 1.5f);
    HostTensor v({out});
    for (float& x : v.data) x = var(rng_);
    w_.add(bn + ".running_var", std::move(v));
}

void RandomWeights::mlp(const std::string& prefix, const std::vector<int64_t>& sizes) {
    for (size_t i = 0; i + 1 < sizes.size(); ++i) {
        const std::string l = prefix + "." + std::to_string(2 * i);
        normal(l + ".weight", {sizes[i + 1], sizes[i]}, 1.0 / std::sqrt(double(sizes[i])));
        normal(l + ".bias", {sizes[i + 1]}, 0.1);
    }
}

}  // namespace vtloc::bench
