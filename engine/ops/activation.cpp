// Elementwise activations: relu, leaky_relu(slope), tanh, sigmoid -> shaders/activation.comp
#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

float slope_of(const Params& p) { return float(p.get("slope", 0.01)); }

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    expect_input_count(in, 1, 1);
    expect_f32(in);
    return {in[0]};
}

template <uint32_t ACT>
void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const float slope = slope_of(p);
    for (size_t i = 0; i < in[0]->data.size(); ++i) out[0]->data[i] = apply_act(in[0]->data[i], ACT, slope);
}

template <uint32_t ACT>
void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    uint32_t local = elementwise_local_size(d);
    const rt::Pipeline& pipe = pipeline(a.ctx, "activation", 2, 8, {local, ACT});
    struct { uint32_t n; float slope; } push{to_u32(numel(a.in[0].shape), "tensor size"), slope_of(a.params)};
    a.seq.dispatch(pipe, {{a.in[0].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write}}, &push,
                   sizeof(push), grid_groups(push.n, local, d));
}

}  // namespace

const OpDef op_relu{"relu", infer, cpu<kActRelu>, gpu<kActRelu>, 0, {"slope"}};
const OpDef op_leaky_relu{"leaky_relu", infer, cpu<kActLeaky>, gpu<kActLeaky>, 0, {"slope"}};
const OpDef op_tanh{"tanh", infer, cpu<kActTanh>, gpu<kActTanh>, 0, {"slope"}};
const OpDef op_sigmoid{"sigmoid", infer, cpu<kActSigmoid>, gpu<kActSigmoid>, 0, {"slope"}};

}  // namespace vtloc::ops
