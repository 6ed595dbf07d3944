#include "engine/model/vtloc_graph.h"

#include <vector>

#include "base/error.h"
#include "engine/model/gma.h"
#include "engine/model/heads.h"
#include "engine/model/point_encoder.h"
#include "engine/model/tactile_encoder.h"
#include "engine/ops/build.h"

namespace vtloc {

const std::vector<TouchOutput>& touch_outputs() {
    static const std::vector<TouchOutput> names{
        {"tactile.input", true}, {"tactile.feature", true}, {"gma.cloud", true},  {"gma.chamfer", false},
        {"ilu.c", false},        {"contact", false},        {"topk.index", false}, {"topk.score", false},
        {"heatmap", false}};
    return names;
}

Graph build_vtloc_graph(const ModelConfig& cfg, const WeightStore& w, const VtlocGraphSpec& spec) {
    const bool normals = cfg.point.use_normals;
    const bool gma = spec.gma && cfg.gma.has_value();
    if (spec.batch < 1) throw Error("a batch holds at least one touch");
    if (spec.n_points <= 0) throw Error("the object cloud is empty");
    const int64_t B = spec.batch;
    const bool batched = B > 1;
    if (batched && spec.ilu_stepped)
        throw Error("the stepped ILU (a bench measurement) runs one touch per graph, not a batch of " + std::to_string(B));

    Graph g;
    int cloud = -1, fp = -1;
    if (spec.encode_object || gma || spec.n_candidates > 0)
        cloud = g.input("point.cloud", {spec.n_points, normals ? 6 : 3});
    if (spec.encode_object) {
        PointEncoderOptions po;
        po.point_major_rows = spec.point_major_rows;
        PointEncoderOutputs p = build_point_encoder(g, w, cfg, cloud, po);
        for (auto& [name, id] : p.indices) g.output(id, name);
        fp = p.feature;
        g.output(fp, "point.feature");
    } else {
        fp = g.input("point.feature", {1, cfg.C});
    }
    if (spec.image_height <= 0) return g;  // the object branch alone

    int gma_target = !gma ? -1 : normals ? cloud : g.input("gma.target", {spec.n_points, 6});
    int iters = cfg.head == Head::Ilu ? g.input("ilu.iters", {1}, ElemType::I32) : -1;
    int candidates = spec.n_candidates > 0 ? g.input("candidates", {spec.n_candidates, 3}) : -1;
    int symmetry = spec.symmetry_order > 1 ? g.input("symmetry", {spec.symmetry_order, 12}) : -1;
    const int64_t k = spec.k > 0 ? spec.k : cfg.K;

    // Every layer takes the whole batch, so the graph's size does not depend on B:
    // one tactile encoder over the images, GMA and the head over all rows, one
    // top-K and heat-map pass per batch.
    Shape image_shape{spec.image_height, spec.image_width, 3};
    if (batched) image_shape.insert(image_shape.begin(), B);
    const int x = add_tactile_preprocess(g, cfg, g.input("tactile.image", image_shape, ElemType::I32));
    g.output(x, "tactile.input");
    const int ft = build_tactile_encoder(g, w, cfg, x);
    g.output(ft, "tactile.feature");
    // Layers that take [F^t, F^p] rows need F^p once per touch; the ILU reads it once.
    const bool rows_needed = batched && (gma || cfg.head != Head::Ilu);
    const int fp_rows = rows_needed ? ops::stack(g, std::vector<int>(size_t(B), fp), "point.feature_rows") : fp;
    if (gma) {
        const int pd = build_gma(g, w, cfg, ft, fp_rows);
        g.output(pd, "gma.cloud");
        g.output(ops::chamfer(g, pd, gma_target, "gma.chamfer").at(0), "gma.chamfer");
    }
    int contact = -1;
    std::vector<int> top;  // top-K index, score, heat-map
    if (cfg.head == Head::Ilu) {
        IluOutputs ilu;
        if (!spec.ilu_stepped && !spec.retrieval_apart && candidates >= 0) {
            // The ILU and retrieval as one node: one dispatch where both fit their
            // register shaders (engine/ops/ilu_retrieve.cpp).
            IluRetrieveOutputs r = build_ilu_retrieve(g, w, ft, fp, iters, spec.max_iters, candidates, cloud, symmetry, k);
            ilu = r.ilu;
            top = {r.index, r.score, r.heat};
        } else {
            ilu = spec.ilu_stepped ? build_ilu_stepped(g, w, ft, fp, iters, spec.max_iters)
                                   : build_ilu(g, w, ft, fp, iters, spec.max_iters);
        }
        g.output(ilu.c, "ilu.c");
        contact = ilu.contact;
    } else {
        contact = build_mcr(g, w, cfg, ft, fp_rows);
    }
    g.output(contact, "contact");
    if (candidates < 0) return g;
    // Top-K and heat-map as one node: one dispatch where both fit one subgroup.
    if (top.empty()) top = ops::retrieve(g, contact, candidates, cloud, symmetry, k, "retrieve");
    g.output(top.at(0), "topk.index");
    g.output(top.at(1), "topk.score");
    g.output(top.at(2), "heatmap");
    return g;
}

}  // namespace vtloc
