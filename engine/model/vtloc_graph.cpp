#include "engine/model/vtloc_graph.h"

#include <vector>

#include "base/error.h"
#include "engine/model/gma.h"
#include "engine/model/heads.h"
#include "engine/model/point_encoder.h"
#include "engine/model/tactile_encoder.h"
#include "engine/ops/build.h"

namespace vtloc {

std::string touch_suffix(int64_t b, int64_t batch) {
    std::string s;
    if (batch != 1) s.append("/").append(std::to_string(b));  // not "/" + ...: GCC 12 -Wrestrict false positive
    return s;
}

Graph build_vtloc_graph(const ModelConfig& cfg, const WeightStore& w, const VtlocGraphSpec& spec) {
    const int64_t C = cfg.C;
    const bool normals = cfg.point.use_normals;
    const bool ilu_head = cfg.head == Head::Ilu;
    const bool gma = spec.gma && cfg.gma.has_value();
    const bool touches = spec.image_height > 0;
    if (spec.batch < 1) throw Error("a batch holds at least one touch");
    if (spec.n_points <= 0) throw Error("the object cloud is empty");

    Graph g;
    int cloud = -1, fp = -1;
    if (spec.encode_object || gma || spec.n_candidates > 0)
        cloud = g.input("point.cloud", {spec.n_points, normals ? 6 : 3});
    if (spec.encode_object) {
        PointEncoderOutputs p = build_point_encoder(g, w, cfg, cloud);
        for (auto& [name, id] : p.indices) g.output(id, name);
        fp = p.feature;
        g.output(fp, "point.feature");
    } else {
        fp = g.input("point.feature", {1, C});
    }
    if (!touches) return g;

    int gma_target = !gma ? -1 : normals ? cloud : g.input("gma.target", {spec.n_points, 6});
    int iters = ilu_head ? g.input("ilu.iters", {1}, ElemType::I32) : -1;
    int candidates = spec.n_candidates > 0 ? g.input("candidates", {spec.n_candidates, 3}) : -1;
    int symmetry = spec.symmetry_order > 1 ? g.input("symmetry", {spec.symmetry_order, 12}) : -1;
    const int64_t k = spec.k > 0 ? spec.k : cfg.K;

    // One tactile encoder over all of the batch's images, one GMA over all its rows
    // and one ILU over all its states (weights read once per batch, dispatches
    // independent of its size); each touch then takes its own rows back for
    // retrieval and the heat-map.
    const bool batched = spec.batch > 1;
    std::vector<int> inputs;
    for (int64_t b = 0; b < spec.batch; ++b) {
        const std::string s = touch_suffix(b, spec.batch);
        int image = g.input("tactile.image" + s, {spec.image_height, spec.image_width, 3}, ElemType::I32);
        inputs.push_back(add_tactile_preprocess(g, cfg, image));
        g.output(inputs.back(), "tactile.input" + s);
    }
    const int ft_all = build_tactile_encoder(g, w, cfg, batched ? ops::stack(g, inputs, "tactile.batch") : inputs[0]);
    int pd_all = -1;
    if (gma) {
        const int fp_rows = batched ? ops::stack(g, std::vector<int>(size_t(spec.batch), fp), "gma.point_rows") : fp;
        pd_all = build_gma(g, w, cfg, ft_all, fp_rows);
    }
    const bool ilu_batched = ilu_head && batched && !spec.ilu_stepped;
    const IluOutputs ilu_all = ilu_batched ? build_ilu(g, w, ft_all, fp, iters, spec.max_iters) : IluOutputs{};

    for (int64_t b = 0; b < spec.batch; ++b) {
        const std::string s = touch_suffix(b, spec.batch);
        const int ft = batched ? ops::rows(g, ft_all, b, 1, "tactile.feature" + s) : ft_all;
        g.output(ft, "tactile.feature" + s);
        if (gma) {
            const int pd = batched ? ops::rows(g, pd_all, b, 1, "gma.cloud" + s) : pd_all;
            g.output(pd, "gma.cloud" + s);
            g.output(ops::chamfer(g, pd, gma_target, "gma.chamfer" + s).at(0), "gma.chamfer" + s);
        }
        int contact;
        if (ilu_batched) {
            g.output(ops::rows(g, ilu_all.c, b, 1, "ilu.c" + s), "ilu.c" + s);
            contact = ops::rows(g, ilu_all.contact, b, 1, "contact" + s);
        } else if (ilu_head) {
            IluOutputs ilu = spec.ilu_stepped ? build_ilu_stepped(g, w, ft, fp, iters, spec.max_iters)
                                               : build_ilu(g, w, ft, fp, iters, spec.max_iters);
            g.output(ilu.c, "ilu.c" + s);
            contact = ilu.contact;
        } else {
            contact = build_mcr(g, w, cfg, ft, fp);
        }
        g.output(contact, "contact" + s);
        if (candidates < 0) continue;
        auto top = ops::topk(g, contact, candidates, k, "topk" + s);
        g.output(top.at(0), "topk.index" + s);
        g.output(top.at(1), "topk.score" + s);
        g.output(ops::heatmap(g, cloud, candidates, top.at(0), symmetry, "heatmap" + s), "heatmap" + s);
    }
    return g;
}

}  // namespace vtloc
