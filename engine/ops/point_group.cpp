// The unfused grouping ops of a set-abstraction scale (group_linear fuses both
// into its GEMMs; these stay as the plain path and its cross-check).
// point_group: [points, centres, idx(, features)] -> [S * NS, CF + 3], rows
//   [features, xyz - centre] (SPEC 2: features first; see point_common.h).
//   -> shaders/point_group.comp. Param feat_begin (features' first column).
// group_max: x [M, C], param group (NS, dividing M) -> [M / NS, C], the max over
//   each NS consecutive rows (the max over a centre's neighbours). With param
//   channel_major = 1, x is [C, M] (group_linear's layout); the output is the same.
//   -> shaders/group_max.comp.
#include <algorithm>
#include <limits>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"
#include "engine/ops/point_common.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> group_infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 3, 4);
    GatherShape g = gather_shape(in[0], in[1], in[2], in.size() == 4 ? &in[3] : nullptr, p);
    to_u32(g.rows() * g.K(), "grouped size");
    to_u32(g.P * std::max(g.D, g.DF), "point array size");
    return {TensorDesc{{g.rows(), g.K()}}};
}

void group_cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const HostTensor* feat = in.size() == 4 ? in[3] : nullptr;
    std::vector<TensorDesc> d{{in[0]->shape}, {in[1]->shape}, {in[2]->shape, ElemType::I32}};
    if (feat) d.push_back({feat->shape});
    GatherShape g = gather_shape(d[0], d[1], d[2], feat ? &d[3] : nullptr, p);
    for (int64_t m = 0; m < g.rows(); ++m)
        for (int64_t k = 0; k < g.K(); ++k)
            out[0]->data[size_t(m * g.K() + k)] = gather_value(*in[0], *in[1], *in[2], feat, g, m, k);
}

void group_gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    std::vector<TensorDesc> ds;
    for (const GpuTensor& t : a.in) ds.push_back({t.shape, ds.size() == 2 ? ElemType::I32 : ElemType::F32});
    GatherShape g = gather_shape(ds[0], ds[1], ds[2], a.in.size() == 4 ? &ds[3] : nullptr, a.params);
    const uint32_t local = elementwise_local_size(d);
    struct { uint32_t rows, NS, P, D, DF, FB, CF; } push{uint32_t(g.rows()), uint32_t(g.NS), uint32_t(g.P),
                                                         uint32_t(g.D), uint32_t(g.DF), uint32_t(g.FB), uint32_t(g.CF)};
    // Without features the points buffer fills the binding; the shader never reads it (CF = 0).
    const rt::BufferView& feat = a.in.size() == 4 ? a.in[3].view : a.in[0].view;
    a.seq.dispatch(pipeline(a.ctx, "point_group", 5, sizeof(push), {local}),
                   {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read},
                    {a.in[2].view, rt::Access::Read}, {feat, rt::Access::Read}, {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), grid_groups(uint64_t(g.rows() * g.K()), local, d));
}

std::vector<TensorDesc> max_infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 1, 1);
    expect_f32(in);
    const Shape& s = in[0].shape;
    if (s.size() != 2) throw Error("input must be [M, C] or channel-major [C, M], got " + shape_str(s));
    const bool cm = p.get("channel_major", 0) != 0;
    const int64_t M = s[cm ? 1 : 0], C = s[cm ? 0 : 1];
    const int64_t ns = int_param(p, "group", 1, std::max<int64_t>(1, M));
    if (M % ns != 0) throw Error(std::to_string(M) + " rows do not split into groups of " + std::to_string(ns));
    to_u32(numel(s), "input size");
    return {TensorDesc{{M / ns, C}}};
}

void max_cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const int64_t ns = int64_t(p.get("group", 1)), G = out[0]->shape[0], C = out[0]->shape[1], M = G * ns;
    const bool cm = p.get("channel_major", 0) != 0;
    for (int64_t g = 0; g < G; ++g)
        for (int64_t c = 0; c < C; ++c) {
            float m = -std::numeric_limits<float>::infinity();
            for (int64_t j = 0; j < ns; ++j) {
                const int64_t r = g * ns + j;
                m = std::max(m, in[0]->data[size_t(cm ? c * M + r : r * C + c)]);
            }
            out[0]->data[size_t(g * C + c)] = m;
        }
}

void max_gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t local = elementwise_local_size(d);
    struct { uint32_t G, NS, C, channel_major; } push{uint32_t(a.out[0].shape[0]), uint32_t(a.params.get("group", 1)),
                                                      uint32_t(a.out[0].shape[1]), a.params.get("channel_major", 0) != 0};
    a.seq.dispatch(pipeline(a.ctx, "group_max", 2, sizeof(push), {local}),
                   {{a.in[0].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write}}, &push, sizeof(push),
                   grid_groups(uint64_t(push.G) * push.C, local, d));
}

}  // namespace

const OpDef op_point_group{"point_group", group_infer, group_cpu, group_gpu, 0, {"feat_begin"}};
const OpDef op_group_max{"group_max", max_infer, max_cpu, max_gpu, 0, {"group", "channel_major"}};

}  // namespace vtloc::ops
