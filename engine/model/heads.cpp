#include "engine/model/heads.h"

#include "engine/error.h"
#include "engine/model/layers.h"
#include "engine/ops/common.h"

namespace vtloc {

std::vector<int> build_ilu(Graph& g, const WeightStore& w, int ft, int fp, int iters) {
    if (iters < 0 || iters > 64) throw Error("ILU iterations must be in 0..64, got " + std::to_string(iters));
    int h = g.add1("tanh", {ft}, {}, "ilu.h0");
    int x = g.add1("concat", {fp, g.add1("relu", {ft}, {}, "ilu.relu_ft")}, {}, "ilu.x");
    std::vector<int> cs;
    int c = -1;
    for (int k = 0; k < iters; ++k) {
        std::string it = "ilu." + std::to_string(k) + ".";
        int hx = g.add1("concat", {h, x}, {}, it + "hx");
        int z = add_linear(g, w, "ilu.convz", hx, ops::kActSigmoid);
        int r = add_linear(g, w, "ilu.convr", hx, ops::kActSigmoid);
        int rhx = g.add1("concat", {g.add1("mul", {r, h}, {}, it + "rh"), x}, {}, it + "rhx");
        int q = add_linear(g, w, "ilu.convq", rhx, ops::kActTanh);
        // (1 - z) * h + z * q  ==  h + z * (q - h)
        h = g.add1("add", {h, g.add1("mul", {z, g.add1("sub", {q, h}, {}, it + "q-h")}, {}, it + "z*")}, {}, it + "h");
        int delta = add_mlp(g, w, "ilu.head", h, 2);
        c = c < 0 ? delta : g.add1("add", {c, delta}, {}, it + "c");
        cs.push_back(c);
    }
    return cs;
}

int build_mcr(Graph& g, const WeightStore& w, const nlohmann::json& config, int ft, int fp) {
    int fused = g.add1("concat", {ft, fp}, {}, "mcr.fused");
    int layers = int(config.at("mcr").at("hidden").size()) + 1;
    return add_mlp(g, w, "mcr.decoder", fused, layers, ops::kActTanh);
}

}  // namespace vtloc
