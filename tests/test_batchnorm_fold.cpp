// Folding BatchNorm into the layer before it gives the same outputs as
// applying the layer and then BatchNorm (eval mode) by hand.
#include <catch2/catch.hpp>
#include <cmath>

#include "base/error.h"
#include "engine/model/batchnorm_fold.h"
#include "tests/harness.h"

using namespace vtloc;

TEST_CASE("BatchNorm folds into the preceding linear layer", "[model]") {
    const int64_t in = 13, out = 7, rows = 5;
    WeightStore w;
    w.add("fc.weight", test::random_tensor({out, in}, 1));
    w.add("fc.bias", test::random_tensor({out}, 2));
    w.add("bn.weight", test::random_tensor({out}, 3, 0.5f, 1.5f));
    w.add("bn.bias", test::random_tensor({out}, 4));
    w.add("bn.running_mean", test::random_tensor({out}, 5, -0.3f, 0.3f));
    w.add("bn.running_var", test::random_tensor({out}, 6, 0.5f, 1.5f));
    HostTensor x = test::random_tensor({rows, in}, 7);

    for (bool with_bias : {true, false}) {
        WeightStore ws = w;
        if (!with_bias) ws = [&] {
            WeightStore c;
            for (auto& n : w.names())
                if (n != "fc.bias") c.add(n, w.get(n));
            return c;
        }();
        FoldedNames f = fold_batchnorm(ws, "fc", "bn");
        HostTensor want({rows, out}), got({rows, out});
        for (int64_t r = 0; r < rows; ++r)
            for (int64_t o = 0; o < out; ++o) {
                double y = with_bias ? w.get("fc.bias").data[size_t(o)] : 0.0, z = ws.get(f.bias).data[size_t(o)];
                for (int64_t i = 0; i < in; ++i) {
                    y += double(x.data[size_t(r * in + i)]) * w.get("fc.weight").data[size_t(o * in + i)];
                    z += double(x.data[size_t(r * in + i)]) * ws.get(f.weight).data[size_t(o * in + i)];
                }
                auto bn = [&](const char* n) { return double(w.get(std::string("bn.") + n).data[size_t(o)]); };
                want.data[size_t(r * out + o)] =
                    float((y - bn("running_mean")) / std::sqrt(bn("running_var") + 1e-5) * bn("weight") + bn("bias"));
                got.data[size_t(r * out + o)] = float(z);
            }
        test::require_close(got, want, {}, with_bias ? "folded with bias" : "folded without bias");
    }
}

TEST_CASE("BatchNorm folding names missing or mis-shaped statistics", "[model]") {
    WeightStore w;
    w.add("fc.weight", HostTensor({4, 3}));
    w.add("bn.weight", HostTensor({4}));
    w.add("bn.bias", HostTensor({4}));
    w.add("bn.running_mean", HostTensor({4}));
    REQUIRE_THROWS_WITH(fold_batchnorm(w, "fc", "bn"), Catch::Contains("'bn.running_var' is missing"));
    w.add("bn.running_var", HostTensor({5}));
    REQUIRE_THROWS_WITH(fold_batchnorm(w, "fc", "bn"), Catch::Contains("'bn.running_var' has shape [5], expected [4]"));
}
