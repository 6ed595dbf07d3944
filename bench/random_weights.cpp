#include "bench/random_weights.h"

#include <cmath>

#include "engine/model/model_config.h"

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

WeightStore random_point_weights(const nlohmann::json& json, uint32_t seed) {
    const ModelConfig cfg = ModelConfig::parse(json, "random weights");
    const PointConfig& p = cfg.point;
    WeightStore w;
    w.set_config(json);
    RandomWeights r(w, seed);
    int64_t ch = p.use_normals ? 3 : 0;  // SA1's features: the normals
    for (size_t i = 0; i < p.sa.size(); ++i) {
        const std::string sa = "point.sa" + std::to_string(i + 1);
        int64_t next = 0;
        for (size_t s = 0; s < p.sa[i].mlps.size(); ++s) {
            int64_t in = ch + 3;
            for (size_t l = 0; l < p.sa[i].mlps[s].size(); ++l) {
                std::string at = ".";  // built piecewise: GCC 12's -Wrestrict false positive on "." + string
                at.append(std::to_string(s)).append(".").append(std::to_string(l));
                const int64_t out = p.sa[i].mlps[s][l];
                r.conv_bn(sa + ".conv_blocks" + at, sa + ".bn_blocks" + at, {out, in, 1, 1}, true);
                in = out;
            }
            next += in;
        }
        ch = next;
    }
    int64_t in = ch + 3;
    const std::string ga = "point.sa" + std::to_string(p.sa.size() + 1);
    for (size_t l = 0; l < p.group_all.size(); ++l) {
        const int64_t out = p.group_all[l];
        r.conv_bn(ga + ".mlp_convs." + std::to_string(l), ga + ".mlp_bns." + std::to_string(l), {out, in, 1, 1}, true);
        in = out;
    }
    std::vector<int64_t> sizes{in};
    sizes.insert(sizes.end(), p.mlp.begin(), p.mlp.end());
    sizes.push_back(cfg.C);
    r.mlp("point.mlp", sizes);
    return w;
}

}  // namespace vtloc::bench
