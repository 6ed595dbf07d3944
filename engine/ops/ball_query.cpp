// ball_query (SPEC 2): for each centre, the first nsample points in index
// order within radius (d^2 <= r^2), the rest filled with the first found.
// -> shaders/ball_query.comp, one thread per centre over shared-memory tiles, or
// ball_query_subgroup.comp (shuffles, no shared memory) where the device has them.
// Inputs: points [N, D >= 3] (xyz = columns 0..2), centres [S, 3].
// Params: radius (> 0), nsample (>= 1). Output: index I32 [S, nsample].
// r^2 = float(r) * float(r) in single precision, as the reference squares it.
#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"
#include "engine/ops/point_common.h"

namespace vtloc::ops {
namespace {

float radius2(const Params& p) {
    const double r = p.get("radius", 0.0);
    if (!(r > 0.0) || !std::isfinite(float(r))) throw Error("radius must be a positive finite number");
    const float rf = float(r);
    return rf * rf;
}

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 2, 2);
    expect_f32(in);
    const Shape &x = in[0].shape, &c = in[1].shape;
    if (x.size() != 2 || x[1] < 3) throw Error("points must be [N, D >= 3], got " + shape_str(x));
    if (x[0] == 0) throw Error("the point cloud is empty");
    if (c.size() != 2 || c[1] != 3) throw Error("centres must be [S, 3], got " + shape_str(c));
    radius2(p);
    const int64_t ns = int_param(p, "nsample", 1, 1 << 16);
    to_u32(numel(x), "point array size");
    to_u32(c[0] * ns, "ball index array size");
    return {TensorDesc{{c[0], ns}, ElemType::I32}};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const HostTensor &x = *in[0], &c = *in[1];
    require_finite_xyz(x, "ball_query");
    require_finite_xyz(c, "ball_query (centres)");
    const int64_t N = x.shape[0], D = x.shape[1], S = c.shape[0], ns = out[0]->shape[1];
    const float r2 = radius2(p);
    for (int64_t s = 0; s < S; ++s) {
        int64_t found = 0;
        for (int64_t i = 0; i < N && found < ns; ++i)
            if (sqdist3(&x.data[size_t(i * D)], &c.data[size_t(3 * s)]) <= r2)
                out[0]->set_int(size_t(s * ns + found++), int32_t(i));
        if (found == 0) throw Error("ball_query: centre " + std::to_string(s) + " has no point within the radius");
        for (int64_t k = found; k < ns; ++k) out[0]->set_int(size_t(s * ns + k), out[0]->int_at(size_t(s * ns)));
    }
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t S = to_u32(a.in[1].shape[0], "centres");
    // One thread per centre: up to 64 (whole subgroups), so that a few hundred
    // centres still spread over several workgroups (cores); the tile is one
    // point (16 bytes of shared memory) per thread.
    uint32_t L = std::min({64u, d.max_invocations, d.max_workgroup_size[0], d.max_shared_memory / 16});
    const uint32_t sg = std::max(1u, d.subgroup_size);
    if (L >= sg) L = L / sg * sg;
    while (L > sg && L / 2 >= S) L /= 2;  // a handful of centres: do not scan with idle threads
    const uint32_t groups = (S + L - 1) / L;
    if (groups > d.max_workgroup_count[0]) throw Error("too many ball-query centres for one dispatch");
    struct { uint32_t N, D, S, NS; float r2; } push{to_u32(a.in[0].shape[0], "points"),
                                                    to_u32(a.in[0].shape[1], "point width"), S,
                                                    to_u32(a.out[0].shape[1], "nsample"), radius2(a.params)};
    // A thread may scan every point (a centre that finds fewer than nsample).
    check_loop_budget(d, uint64_t(push.N) + push.N / L + 2 * uint64_t(push.NS) + 8,
                      "ball query over " + std::to_string(push.N) + " points");
    // ball_query_subgroup.comp: shuffles instead of shared-memory tiles, the cloud
    // as texels; param subgroup = 0 forces the tiled shader.
    const bool subgroup = a.params.get("subgroup", 1) != 0 && shuffles_allowed(a) &&
                          (d.subgroup_ops & VK_SUBGROUP_FEATURE_VOTE_BIT) && sg <= 32 && L % sg == 0 &&
                          uint64_t(numel(a.in[0].shape)) <= d.max_texel_elements;
    const rt::Access R = rt::Access::Read;
    if (subgroup)
        a.seq.dispatch(a.ctx.pipelines().get(rt::PipelineDesc{"ball_query_subgroup", 3, sizeof(push), {L, sg}, 0x1u}),
                       {{a.in[0].view, R, VK_FORMAT_R32_SFLOAT}, {a.in[1].view, R}, {a.out[0].view, rt::Access::Write}},
                       &push, sizeof(push), std::max(1u, groups));
    else
        a.seq.dispatch(pipeline(a.ctx, "ball_query", 3, sizeof(push), {L}),
                       {{a.in[0].view, R}, {a.in[1].view, R}, {a.out[0].view, rt::Access::Write}}, &push, sizeof(push),
                       std::max(1u, groups));
}

}  // namespace

const OpDef op_ball_query{"ball_query", infer, cpu, gpu, 0, {"radius", "nsample", "subgroup"}};

}  // namespace vtloc::ops
