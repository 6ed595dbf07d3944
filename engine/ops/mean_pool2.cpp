// mean_pool2: x [H, W] or [H, W, C] -> [ceil(H/2), ceil(W/2)(, C)], each output pixel the mean of
// its block of up to 2 x 2 input pixels. The Poisson solve's coarse grids (the gradient and the
// mask halved; engine/sensor/gel_shape_gpu). CPU reference gel::mean_pool2 (engine/ops/gel_ops.h)
// -> shaders/mean_pool2.comp, a lane per output element.
#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/gel_ops.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    expect_input_count(in, 1, 1);
    expect_f32(in);
    const Shape& x = in[0].shape;
    if ((x.size() != 2 && x.size() != 3) || x[0] < 1 || x[1] < 1 || (x.size() == 3 && x[2] < 1))
        throw Error("mean_pool2: the input must be [H, W] or [H, W, C], got " + shape_str(x));
    to_u32(x[0] * x[1] * (x.size() == 3 ? x[2] : 1), "mean_pool2 input size");
    Shape y = x;
    y[0] = (x[0] + 1) / 2, y[1] = (x[1] + 1) / 2;
    return {TensorDesc{y}};
}

int channels(const Shape& s) { return s.size() == 3 ? int(s[2]) : 1; }

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    const Shape& x = in[0]->shape;
    gel::mean_pool2(in[0]->data.data(), int(x[0]), int(x[1]), channels(x), out[0]->data.data());
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const Shape& x = a.in[0].shape;
    struct { int32_t H, W, C; } push{int32_t(x[0]), int32_t(x[1]), int32_t(channels(x))};
    const uint64_t n = uint64_t((x[0] + 1) / 2) * uint64_t((x[1] + 1) / 2) * uint64_t(push.C);
    const uint32_t local = fill_local_size(d, n), groups = grid_groups(n, local, d);
    check_loop_budget(d, (n + uint64_t(groups) * local - 1) / (uint64_t(groups) * local), "mean_pool2");
    a.seq.dispatch(pipeline(a.ctx, "mean_pool2", 2, sizeof(push), {local}),
                   {{a.in[0].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write}}, &push, sizeof(push), groups);
}

}  // namespace

const OpDef op_mean_pool2{"mean_pool2", infer, cpu, gpu, 0, {}};

}  // namespace vtloc::ops
