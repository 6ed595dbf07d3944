// sa_gather: layer one of a set-abstraction MLP from its per-point part.
// Layer one is linear before its activation, so on the row (s, j) = [features of
// q, xyz of q - centre s] it equals U[q] - W_xyz c_s, with U = W [features, xyz] + b
// computed once per source point (group_linear, input Points). The paper's SA2
// has 512 source points but 128 x (32 + 64 + 128) rows: layer one's work drops
// by that ratio, and this op only gathers and subtracts.
// Inputs: U [N, P] (channel-major: group_linear's output), centres [S, 3], idx
// I32 [S, NS] (the ball), W^T [K, N] (the layer's input-major weight; rows K-3..K-1
// are its xyz part). Params act, slope, texel (0: U and W from storage buffers).
// Output [N, S * NS] channel-major, the next group_linear's Rows input.
// -> shaders/sa_gather.comp (U and W as texel buffers) or sa_gather_ssbo.comp.
// The point encoder computes these rows inside the next layer instead (group_linear,
// hidden = 2) wherever the width is a multiple of 4, and uses this op elsewhere.
#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"
#include "engine/ops/point_common.h"

namespace vtloc::ops {
namespace {

struct Dims {
    int64_t N, P, S, NS, K;
};

Dims dims(const std::vector<TensorDesc>& in) {
    expect_input_count(in, 4, 4);
    if (in[0].type != ElemType::F32 || in[1].type != ElemType::F32 || in[3].type != ElemType::F32)
        throw Error("U, centres and the weight must be F32");
    if (in[2].type != ElemType::I32) throw Error("ball indices must be I32");
    const Shape &u = in[0].shape, &c = in[1].shape, &idx = in[2].shape, &w = in[3].shape;
    if (u.size() != 2 || u[0] == 0 || u[1] == 0) throw Error("U must be channel-major [N, P], got " + shape_str(u));
    if (c.size() != 2 || c[1] != 3) throw Error("centres must be [S, 3], got " + shape_str(c));
    if (idx.size() != 2 || idx[0] != c[0] || idx[1] == 0)
        throw Error("ball indices " + shape_str(idx) + " must be [S, nsample] for centres " + shape_str(c));
    if (w.size() != 2 || w[1] != u[0] || w[0] < 3)
        throw Error("weight " + shape_str(w) + " must be input-major [K >= 3, " + std::to_string(u[0]) + "]");
    Dims d{u[0], u[1], c[0], idx[1], w[0]};
    to_u32(d.N * d.S * d.NS, "output size");
    to_u32(d.N * d.P, "U size");
    to_u32(d.K * d.N, "weight size");
    return d;
}

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    const Dims d = dims(in);
    return {TensorDesc{{d.N, d.S * d.NS}}};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    std::vector<TensorDesc> ds;
    for (const HostTensor* t : in) ds.push_back({t->shape, t->type});
    const Dims d = dims(ds);
    const uint32_t act = uint32_t(p.get("act", kActNone));
    const float slope = float(p.get("slope", 0.01));
    const HostTensor &u = *in[0], &c = *in[1], &idx = *in[2], &w = *in[3];
    const int64_t M = d.S * d.NS;
    for (int64_t m = 0; m < M; ++m) {
        const int32_t q = ball_point(idx, m, d.P);
        const float* cs = &c.data[size_t(3 * (m / d.NS))];
        for (int64_t n = 0; n < d.N; ++n)
            out[0]->data[size_t(n * M + m)] =
                apply_act(float(u.data[size_t(n * d.P + q)] - centre_share(w, d.K - 3, d.N, n, cs)), act, slope);
    }
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& dev = a.ctx.info();
    std::vector<TensorDesc> ds;
    for (size_t i = 0; i < a.in.size(); ++i) ds.push_back({a.in[i].shape, i == 2 ? ElemType::I32 : ElemType::F32});
    const Dims d = dims(ds);
    const uint64_t M = uint64_t(d.S * d.NS);
    const uint32_t local = elementwise_local_size(dev);
    struct { uint32_t M, NS, P, K, N, act; float slope; } push{uint32_t(M), uint32_t(d.NS), uint32_t(d.P), uint32_t(d.K),
                                                              uint32_t(d.N), uint32_t(a.params.get("act", kActNone)),
                                                              float(a.params.get("slope", 0.01))};
    // U and W through texel buffers where the device's limit allows (a gather on lavapipe).
    const bool texel = texels_allowed(a, {uint64_t(d.N * d.P), uint64_t(d.K * d.N)});
    const rt::Access R = rt::Access::Read;
    const bool row4 = M % 4 == 0;
    rt::PipelineDesc desc{texel ? "sa_gather" : "sa_gather_ssbo", 5, sizeof(push), {local, row4}, texel ? 0x9u : 0u};
    a.seq.dispatch(a.ctx.pipelines().get(desc),
                   {{a.in[0].view, R, texel ? VK_FORMAT_R32_SFLOAT : VK_FORMAT_UNDEFINED}, {a.in[1].view, R},
                    {a.in[2].view, R}, {a.in[3].view, R, texel ? VK_FORMAT_R32_SFLOAT : VK_FORMAT_UNDEFINED},
                    {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), grid_groups(row4 ? M / 4 : M, local, dev));
}

}  // namespace

const OpDef op_sa_gather{"sa_gather", infer, cpu, gpu, 0, {"act", "slope", "texel"}};

}  // namespace vtloc::ops
