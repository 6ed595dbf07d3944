#include "engine/model/point_encoder.h"

#include <cmath>

#include "base/error.h"
#include "engine/model/prepared_weights.h"
#include "engine/model/layers.h"
#include "engine/ops/build.h"
#include "engine/ops/common.h"
#include "engine/ops/point_common.h"
#include "runtime/context.h"

namespace vtloc {

namespace {

// A 1x1 Conv2d with its BatchNorm folded (prepare_weights): the weight as [out, in]
// (linear's layout) or, for group_linear, input-major [in, out]; and the bias.
std::pair<int, int> conv_bn(Graph& g, const WeightStore& w, const std::string& conv, int64_t in, int64_t out,
                            bool input_major) {
    const HostTensor& t = prepared_tensor(w, prepared::point_2d(conv), conv);
    if (t.shape != Shape{out, in})  // named as the file's tensor: the file disagrees with the config
        throw Error("weight '" + conv + ".weight' has shape " + shape_str({t.shape.at(0), t.shape.at(1), 1, 1}) +
                    ", expected " + shape_str({out, in, 1, 1}));
    return {input_major ? g.weight(prepared::point_kn(conv), {in, out}) : g.weight(prepared::point_2d(conv), {out, in}),
            g.weight(prepared::bias(conv), {out})};
}

// Layer one of a scale is computed per source point (sa_gather.cpp) when its
// input is wider than this: the gather costs about as much per output as 100
// multiply-adds of the direct layer on lavapipe (measured 2026-11-24: 8 ns
// against 0.08 ns per multiply-add), so only the paper's SA2 (323 inputs) gains.
constexpr int64_t kFactorFromK = 128;

// A stage's input: xyz in columns 0..2 of `xyz`, features in columns feat_begin.. of `feat`
// (-1: none), `channels` feature columns, `points` rows.
struct StageInput {
    int xyz, feat;
    int64_t feat_begin, channels, points;
};

// Scale `s` of a set-abstraction stage: the ball around each centre, its shared MLP and the
// max over the ball's points.
int sa_scale(Graph& g, const WeightStore& w, const SaStageConfig& st, size_t s, const std::string& pre,
             const StageInput& si_in, int centres, const PointEncoderOptions& opt, PointEncoderOutputs& out) {
    const bool fuse = opt.fuse;
    const std::string si = std::to_string(s), ball_name = pre + ".ball." + si;
    const int64_t ns = st.nsample[s];
    int ball = ops::ball_query(g, si_in.xyz, centres, st.radii[s], ns, ball_name);
    out.indices.push_back({ball_name, ball});
    std::vector<int> gather_in{si_in.xyz, centres, ball};
    const int64_t fb = si_in.feat_begin;
    const int feat = si_in.feat;
    int x = -1;
    if (!fuse) {
        if (feat >= 0) gather_in.push_back(feat);
        x = ops::point_group(g, gather_in, fb, pre + ".group." + si);
    }
    int64_t in = si_in.channels + 3;
    const std::vector<int64_t>& widths = st.mlps[s];
    // Fused, layer one is computed inside layer two (group_linear's hidden input)
    // and never stored: on lavapipe (AVX2) storing it cost more than computing it.
    // A narrow one (<= 4 features + xyz) from the gathered row; a wide one once
    // per source point, each ball row then taking its point's value less the
    // centre's share (as sa_gather.cpp, which is left for widths that are not a
    // multiple of 4).
    using Hidden = ops::GroupLinear::Hidden;
    // Not for a one-layer MLP: that layer is also the max, which the per-point path lacks.
    const bool per_point = widths.size() > 1 && si_in.channels + 3 > kFactorFromK && si_in.points < st.npoint * ns;
    Hidden hidden = Hidden::None;
    if (fuse && widths.size() > 1 && widths[0] % 4 == 0)
        hidden = si_in.channels <= 4 ? Hidden::Gathered : per_point ? Hidden::PerPoint : Hidden::None;
    std::pair<int, int> first{-1, -1};
    int u = -1;  // Hidden::PerPoint: layer one per source point, point-major
    bool x_pm = false;  // x is point-major rows [M, C] (a group_linear's, opt.point_major_rows)
    for (size_t l = 0; l < widths.size(); ++l) {
        const std::string node = pre + ".conv_blocks." + si + "." + std::to_string(l);
        auto [wv, bv] = conv_bn(g, w, node, in, widths[l], fuse);
        in = widths[l];
        if (!fuse) {
            x = ops::linear(g, x, wv, bv, ops::kActRelu, 0.01, node);
            continue;
        }
        // Fused: the first layer gathers its rows from the cloud, the last
        // one keeps only the max over each centre's neighbours.
        if (l == 0 && (per_point || hidden != Hidden::None)) {
            first = {wv, bv};
            if (hidden == Hidden::Gathered) continue;
            ops::GroupLinear pl;
            pl.input = ops::GroupLinear::Input::Points;
            pl.feat_begin = fb;
            pl.point_major = hidden == Hidden::PerPoint;
            std::vector<int> pins{si_in.xyz, wv, bv};
            if (feat >= 0) pins.push_back(feat);
            u = ops::group_linear(g, pins, pl, node + ".points");
            if (hidden == Hidden::None) x = ops::sa_gather(g, u, centres, ball, wv, ops::kActRelu, node);
            continue;
        }
        ops::GroupLinear gl;
        gl.act = ops::kActRelu;
        std::vector<int> ins{x};
        const bool gather = l == 0 || (hidden != Hidden::None && l == 1);
        if (gather) {
            gl.input = ops::GroupLinear::Input::Gather;
            gl.feat_begin = fb;
            gl.hidden = l == 1 ? hidden : Hidden::None;
            if (gl.hidden == Hidden::PerPoint) {
                ins = {u, centres, ball, first.first};
            } else {
                ins = gather_in;
                if (gl.hidden == Hidden::Gathered) ins.push_back(first.first), ins.push_back(first.second);
            }
        }
        ins.push_back(wv);
        ins.push_back(bv);
        if (gather && feat >= 0 && gl.hidden != Hidden::PerPoint) ins.push_back(feat);
        gl.max = l + 1 == widths.size();
        gl.group = ns;
        gl.x_point_major = !gather && x_pm;
        gl.point_major = !gl.max && opt.point_major_rows;
        gl.fill = opt.fill;
        // Ball padding (a ball's free slots repeat its first point) is skipped:
        // the max leaves it out, and a gathering layer right before it leaves it
        // unwritten (not one with rows layers between: they would compute on
        // whatever the skipped rows hold, for nothing). docs/performance.md "Ball padding".
        gl.skip_padding = opt.skip_padding && (gl.max || (gather && l + 2 == widths.size()));
        if (gl.skip_padding && !gather && gl.max) ins.push_back(ball);
        x = ops::group_linear(g, ins, gl, node);
        x_pm = gl.point_major;
    }
    if (!fuse) x = ops::group_max(g, x, ns, false, pre + ".max." + si);
    return x;
}

// Group all: one group of every point, input [xyz, features] (xyz first, not centred).
int group_all(Graph& g, const WeightStore& w, const PointConfig& c, const StageInput& st, bool fuse) {
    const std::string pre = "point.sa" + std::to_string(c.sa.size() + 1);
    int x = fuse ? -1 : ops::concat(g, {st.xyz, st.feat}, pre + ".input");
    int64_t in = st.channels + 3;
    for (size_t l = 0; l < c.group_all.size(); ++l) {
        const std::string node = pre + ".mlp_convs." + std::to_string(l);
        auto [wv, bv] = conv_bn(g, w, node, in, c.group_all[l], fuse);
        in = c.group_all[l];
        if (!fuse) {
            x = ops::linear(g, x, wv, bv, ops::kActRelu, 0.01, node);
            continue;
        }
        // Not fused with the max: one group leaves too few invocations for the
        // fused layer's group-per-invocation max; a separate max is cheap.
        ops::GroupLinear gl;
        gl.act = ops::kActRelu;
        if (l == 0) gl.input = ops::GroupLinear::Input::GroupAll;
        std::vector<int> ins = l == 0 ? std::vector<int>{st.xyz, wv, bv, st.feat} : std::vector<int>{x, wv, bv};
        x = ops::group_linear(g, ins, gl, node);
    }
    return ops::group_max(g, x, st.points, fuse, pre + ".max");
}

}  // namespace

bool point_major_rows_on(const rt::DeviceInfo* device) { return !device || device->type == VK_PHYSICAL_DEVICE_TYPE_CPU; }

PointEncoderOutputs build_point_encoder(Graph& g, const WeightStore& w, const ModelConfig& config, int cloud) {
    return build_point_encoder(g, w, config, cloud, PointEncoderOptions{});
}

PointEncoderOutputs build_point_encoder(Graph& g, const WeightStore& w, const ModelConfig& config, int cloud,
                                        const PointEncoderOptions& options) {
    const PointConfig& c = config.point;
    const Shape& cs = g.value(cloud).shape;
    const int64_t width = c.use_normals ? 6 : 3;
    if (cs.size() != 2 || cs[1] != width)
        throw Error(std::string("the point cloud must be [N, ") + (c.use_normals ? "6] (xyz, normals)" : "3] (xyz)") +
                    " for this config, got " + shape_str(cs));
    if (cs[0] == 0) throw Error("the point cloud is empty");
    if (g.value(cloud).type != ElemType::F32) throw Error("the point cloud must be F32");

    PointEncoderOutputs out;
    StageInput st_in{cloud, c.use_normals ? cloud : -1, c.use_normals ? 3 : 0, c.use_normals ? 3 : 0, cs[0]};
    for (size_t i = 0; i < c.sa.size(); ++i) {
        const SaStageConfig& st = c.sa[i];
        const std::string pre = "point.sa" + std::to_string(i + 1);
        if (st.npoint > st_in.points)
            throw Error(pre + " samples " + std::to_string(st.npoint) + " points but gets only " +
                        std::to_string(st_in.points) + (i == 0 ? " (the cloud is too small for this model)" : ""));
        std::vector<int> fps = ops::fps(g, st_in.xyz, st.npoint, pre + ".fps");
        out.indices.push_back({pre + ".fps", fps[0]});
        const int centres = fps[1];
        std::vector<int> scales;
        int64_t next_channels = 0;
        for (size_t s = 0; s < st.radii.size(); ++s) {
            scales.push_back(sa_scale(g, w, st, s, pre, st_in, centres, options, out));
            next_channels += st.mlps[s].back();
        }
        const int feat = scales.size() == 1 ? scales[0] : ops::concat(g, scales, pre + ".concat");
        st_in = StageInput{centres, feat, 0, next_channels, st.npoint};
    }

    const int x = group_all(g, w, c, st_in, options.fuse);
    out.feature = add_mlp(g, w, "point.mlp", x, int(c.mlp.size()) + 1);
    if (g.value(out.feature).shape != Shape{1, config.C})
        throw Error("point.mlp gives " + shape_str(g.value(out.feature).shape) + ", expected [1, " + std::to_string(config.C) + "]");
    return out;
}

void check_object_cloud(const HostTensor& cloud, const ModelConfig& config) {
    constexpr int64_t width = 6;
    if (cloud.shape.size() != 2 || cloud.shape[1] != width)
        throw Error("the object cloud must be [N, 6] (xyz and normals), got " + shape_str(cloud.shape));
    for (size_t i = 0; i < cloud.data.size(); ++i)
        if (!std::isfinite(cloud.data[i]))
            throw Error("the object cloud has a NaN or infinite value at point " + std::to_string(int64_t(i) / width) +
                        ", column " + std::to_string(int64_t(i) % width));
    if (cloud.shape[0] == 0) throw Error("the object cloud is empty");
    const int64_t need = config.point.min_points();
    if (cloud.shape[0] < need)
        throw Error("the object cloud has " + std::to_string(cloud.shape[0]) + " points, fewer than the " +
                    std::to_string(need) + " that point.sa1 samples; the model needs at least that many");
}

}  // namespace vtloc
