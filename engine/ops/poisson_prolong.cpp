// poisson_prolong: a coarse solve's answer [h, w] and the finer grid's mask [H, W] (h = ceil(H/2),
// w = ceil(W/2)) -> the finer solve's start [H, W]: bilinear, times 2 (z is in pixels, a coarse
// pixel is two), 0 outside the mask. The Poisson solve's coarse-to-fine step
// (engine/sensor/gel_shape_gpu). CPU reference gel::poisson_prolong (engine/ops/gel_ops.h) ->
// shaders/poisson_prolong.comp, a lane per pixel.
#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/gel_ops.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    expect_input_count(in, 2, 2);
    expect_f32(in);
    const Shape &zc = in[0].shape, &m = in[1].shape;
    if (m.size() != 2 || m[0] < 1 || m[1] < 1) throw Error("poisson_prolong: the mask must be [H, W], got " + shape_str(m));
    const Shape want{(m[0] + 1) / 2, (m[1] + 1) / 2};
    if (zc != want) throw Error("poisson_prolong: the coarse answer must be " + shape_str(want) + " for a " + shape_str(m) + " mask, got " + shape_str(zc));
    to_u32(m[0] * m[1], "poisson_prolong size");
    return {TensorDesc{m}};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    const Shape &zc = in[0]->shape, &m = in[1]->shape;
    gel::poisson_prolong(in[0]->data.data(), int(zc[0]), int(zc[1]), in[1]->data.data(), int(m[0]), int(m[1]), out[0]->data.data());
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const Shape &zc = a.in[0].shape, &m = a.in[1].shape;
    struct { int32_t H, W, h, w; } push{int32_t(m[0]), int32_t(m[1]), int32_t(zc[0]), int32_t(zc[1])};
    const uint64_t n = uint64_t(m[0]) * uint64_t(m[1]);
    const uint32_t local = fill_local_size(d, n), groups = grid_groups(n, local, d);
    check_loop_budget(d, (n + uint64_t(groups) * local - 1) / (uint64_t(groups) * local), "poisson_prolong");
    a.seq.dispatch(pipeline(a.ctx, "poisson_prolong", 3, sizeof(push), {local}),
                   {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), groups);
}

}  // namespace

const OpDef op_poisson_prolong{"poisson_prolong", infer, cpu, gpu, 0, {}};

}  // namespace vtloc::ops
