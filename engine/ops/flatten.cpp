// flatten: [N, d1, d2, ...] -> [N, d1 * d2 * ...] (torch.flatten(x, 1)); the
// bytes do not move, so the GPU side is one buffer copy and no shader.
#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    expect_input_count(in, 1, 1);
    const Shape& x = in[0].shape;
    if (x.empty()) throw Error("input must have a batch dimension, got a scalar");
    int64_t rest = 1;
    for (size_t i = 1; i < x.size(); ++i) rest *= x[i];
    return {TensorDesc{Shape{x[0], rest}, in[0].type}};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    out[0]->data = in[0]->data;
}

void gpu(const GpuOpArgs& a) { a.seq.copy(a.in[0].view, a.out[0].view); }

}  // namespace

const OpDef op_flatten{"flatten", infer, cpu, gpu, 0, {}};

}  // namespace vtloc::ops
