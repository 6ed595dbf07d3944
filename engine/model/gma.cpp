#include "engine/model/gma.h"

#include <algorithm>
#include <cstring>

#include "base/error.h"
#include "engine/model/layers.h"
#include "engine/ops/common.h"
#include "engine/ops/build.h"

namespace vtloc {

std::vector<int64_t> plan_row_chunks(int64_t rows, uint64_t row_bytes, uint64_t max_bytes) {
    if (row_bytes > max_bytes)
        throw Error("one row of " + std::to_string(row_bytes) + " bytes exceeds the binding limit of " +
                    std::to_string(max_bytes) + " bytes");
    const int64_t per = row_bytes ? int64_t(max_bytes / row_bytes) : rows;
    std::vector<int64_t> out;
    for (int64_t r = 0; r < rows; r += per) out.push_back(std::min(per, rows - r));
    return out;
}

std::vector<std::string> split_weight_rows(WeightStore& w, const std::string& name, uint64_t max_bytes) {
    const HostTensor& t = w.get(name);
    if (t.shape.empty()) throw Error("weight '" + name + "' is a scalar; it has no rows to split");
    const int64_t rows = t.shape[0];
    const int64_t row_elems = rows ? t.size() / rows : 0;
    std::vector<int64_t> plan = plan_row_chunks(rows, uint64_t(row_elems) * 4, max_bytes);
    if (plan.size() <= 1) return {name};
    // A split made earlier with a smaller limit would leave stale higher chunks bound.
    if (w.has(name + "#" + std::to_string(plan.size())))
        throw Error("weight '" + name + "' was already split into more chunks; split it once");
    std::vector<std::string> names;
    int64_t r0 = 0;
    for (size_t i = 0; i < plan.size(); ++i) {
        Shape s = t.shape;
        s[0] = plan[i];
        HostTensor chunk(s);
        if (!chunk.data.empty())
            std::memcpy(chunk.data.data(), t.data.data() + r0 * row_elems, size_t(plan[i] * row_elems) * 4);
        names.push_back(name + "#" + std::to_string(i));
        r0 += plan[i];
        w.add(names.back(), std::move(chunk));  // `t` stays valid: the store is a std::map
    }
    return names;
}

std::vector<std::string> weight_row_chunks(const WeightStore& w, const std::string& name) {
    std::vector<std::string> names;
    for (size_t i = 0; w.has(name + "#" + std::to_string(i)); ++i) names.push_back(name + "#" + std::to_string(i));
    return names.empty() ? std::vector<std::string>{name} : names;
}

int build_gma(Graph& g, const WeightStore& w, const ModelConfig& config, int ft, int fp) {
    if (!config.gma) throw Error("the config has no GMA");
    const int64_t nd = config.gma->n_points, cd = config.gma->channels;
    std::vector<int> in{ops::concat(g, {ft, fp}, "gma.fused")};
    for (const std::string& n : weight_row_chunks(w, "gma.weight")) in.push_back(g.weight(n, w.get(n).shape));
    const Shape& first = g.value(in[1]).shape;
    if (first.size() != 3 || first[1] != nd || first[2] != cd)
        throw Error("gma.weight chunks are " + shape_str(first) + ", expected [rows, " + std::to_string(nd) + ", " +
                    std::to_string(cd) + "]");
    int x = ops::disentangle(g, in, ops::kActLeaky, 0.01, "gma.disentangle");
    const int layers = int(config.gma->decoder.size()) + 1;
    for (int i = 0; i < layers; ++i)
        x = add_linear(g, w, "gma.decoder." + std::to_string(2 * i), x, i + 1 < layers ? ops::kActLeaky : ops::kActNone, 0.01);
    return ops::gma_decode(g, x, "gma.cloud");
}

}  // namespace vtloc
