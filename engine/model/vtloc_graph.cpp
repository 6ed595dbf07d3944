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

namespace {

// The parts a batch shares: one tactile encoder over all of its images, one GMA
// over all its rows and one ILU over all its states (weights read once per batch,
// dispatches independent of its size). Each touch then takes its own rows back.
struct BatchParts {
    int ft = -1;      // F^t [B, C]
    int pd = -1;      // P^d [B, N^d, 6] (GMA only)
    IluOutputs ilu;   // c [B, max, 3], contact [B, 3] (batched ILU only)
    bool ilu_batched = false;
};

BatchParts build_batch_parts(Graph& g, const ModelConfig& cfg, const WeightStore& w, const VtlocGraphSpec& spec,
                             int fp, bool gma, int iters) {
    const bool batched = spec.batch > 1;
    std::vector<int> inputs;
    for (int64_t b = 0; b < spec.batch; ++b) {
        const std::string s = touch_suffix(b, spec.batch);
        int image = g.input("tactile.image" + s, {spec.image_height, spec.image_width, 3}, ElemType::I32);
        inputs.push_back(add_tactile_preprocess(g, cfg, image));
        g.output(inputs.back(), "tactile.input" + s);
    }
    BatchParts p;
    p.ft = build_tactile_encoder(g, w, cfg, batched ? ops::stack(g, inputs, "tactile.batch") : inputs[0]);
    if (gma) {
        const int fp_rows = batched ? ops::stack(g, std::vector<int>(size_t(spec.batch), fp), "gma.point_rows") : fp;
        p.pd = build_gma(g, w, cfg, p.ft, fp_rows);
    }
    p.ilu_batched = cfg.head == Head::Ilu && batched && !spec.ilu_stepped;
    if (p.ilu_batched) p.ilu = build_ilu(g, w, p.ft, fp, iters, spec.max_iters);
    return p;
}

// Touch b's c^p (outputs ilu.c{s} on the way): its row of the batched ILU, or its own head.
int touch_contact(Graph& g, const ModelConfig& cfg, const WeightStore& w, const VtlocGraphSpec& spec,
                  const BatchParts& p, int ft, int fp, int iters, int64_t b, const std::string& s) {
    if (p.ilu_batched) {
        g.output(ops::rows(g, p.ilu.c, b, 1, "ilu.c" + s), "ilu.c" + s);
        return ops::rows(g, p.ilu.contact, b, 1, "contact" + s);
    }
    if (cfg.head != Head::Ilu) return build_mcr(g, w, cfg, ft, fp);
    IluOutputs ilu = spec.ilu_stepped ? build_ilu_stepped(g, w, ft, fp, iters, spec.max_iters)
                                       : build_ilu(g, w, ft, fp, iters, spec.max_iters);
    g.output(ilu.c, "ilu.c" + s);
    return ilu.contact;
}

}  // namespace

Graph build_vtloc_graph(const ModelConfig& cfg, const WeightStore& w, const VtlocGraphSpec& spec) {
    const bool normals = cfg.point.use_normals;
    const bool gma = spec.gma && cfg.gma.has_value();
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
        fp = g.input("point.feature", {1, cfg.C});
    }
    if (spec.image_height <= 0) return g;  // the object branch alone

    int gma_target = !gma ? -1 : normals ? cloud : g.input("gma.target", {spec.n_points, 6});
    int iters = cfg.head == Head::Ilu ? g.input("ilu.iters", {1}, ElemType::I32) : -1;
    int candidates = spec.n_candidates > 0 ? g.input("candidates", {spec.n_candidates, 3}) : -1;
    int symmetry = spec.symmetry_order > 1 ? g.input("symmetry", {spec.symmetry_order, 12}) : -1;
    const int64_t k = spec.k > 0 ? spec.k : cfg.K;

    const BatchParts parts = build_batch_parts(g, cfg, w, spec, fp, gma, iters);
    const bool batched = spec.batch > 1;
    for (int64_t b = 0; b < spec.batch; ++b) {
        const std::string s = touch_suffix(b, spec.batch);
        const int ft = batched ? ops::rows(g, parts.ft, b, 1, "tactile.feature" + s) : parts.ft;
        g.output(ft, "tactile.feature" + s);
        if (gma) {
            const int pd = batched ? ops::rows(g, parts.pd, b, 1, "gma.cloud" + s) : parts.pd;
            g.output(pd, "gma.cloud" + s);
            g.output(ops::chamfer(g, pd, gma_target, "gma.chamfer" + s).at(0), "gma.chamfer" + s);
        }
        const int contact = touch_contact(g, cfg, w, spec, parts, ft, fp, iters, b, s);
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
