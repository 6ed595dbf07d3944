#include "engine/model/batchnorm_fold.h"

#include <cmath>

#include "base/error.h"

namespace vtloc {

FoldedNames fold_batchnorm(WeightStore& w, const std::string& layer, const std::string& bn, double eps) {
    const HostTensor& weight = w.get(layer + ".weight");
    if (weight.shape.empty()) throw Error("weight '" + layer + ".weight' is a scalar; cannot fold BatchNorm");
    const int64_t out = weight.shape[0];
    const Shape vec{out};
    const HostTensor& gamma = w.get(bn + ".weight", vec);
    const HostTensor& beta = w.get(bn + ".bias", vec);
    const HostTensor& mean = w.get(bn + ".running_mean", vec);
    const HostTensor& var = w.get(bn + ".running_var", vec);
    const HostTensor* bias = w.has(layer + ".bias") ? &w.get(layer + ".bias", vec) : nullptr;

    const int64_t per_out = out ? weight.size() / out : 0;
    HostTensor fw(weight.shape), fb(vec);
    for (int64_t o = 0; o < out; ++o) {
        double v = var.data[size_t(o)];
        if (!(v + eps > 0.0))
            throw Error("BatchNorm '" + bn + "' has a negative running_var at channel " + std::to_string(o));
        double g = gamma.data[size_t(o)] / std::sqrt(v + eps);
        for (int64_t i = 0; i < per_out; ++i)
            fw.data[size_t(o * per_out + i)] = float(weight.data[size_t(o * per_out + i)] * g);
        double b = bias ? bias->data[size_t(o)] : 0.0;
        fb.data[size_t(o)] = float((b - mean.data[size_t(o)]) * g + beta.data[size_t(o)]);
    }
    FoldedNames names{layer + ".weight#bn", layer + ".bias#bn"};
    w.add(names.weight, std::move(fw));
    w.add(names.bias, std::move(fb));
    return names;
}

}  // namespace vtloc
