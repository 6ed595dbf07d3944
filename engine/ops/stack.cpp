// stack: inputs [n_i, d1, d2, ...] with equal trailing dims -> [sum n_i, d1, ...]
// (torch.cat along dim 0). Row-major rows are contiguous, so the GPU side is
// one buffer copy per input into its byte range of the output, and no shader.
// The batched graph uses it to give one tactile encoder all of a batch's images.
#include <cstring>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    if (in.empty()) throw Error("takes at least one input");
    const TensorDesc& first = in[0];
    if (first.shape.empty()) throw Error("cannot stack scalars");
    TensorDesc out = first;
    out.shape[0] = 0;
    for (const TensorDesc& d : in) {
        if (d.type != first.type) throw Error("inputs mix element types");
        if (d.shape.size() != first.shape.size() || !std::equal(d.shape.begin() + 1, d.shape.end(), first.shape.begin() + 1))
            throw Error("shapes " + shape_str(first.shape) + " and " + shape_str(d.shape) + " differ outside the first axis");
        out.shape[0] += d.shape[0];
    }
    return {out};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    size_t at = 0;
    for (const HostTensor* t : in) {
        if (!t->data.empty()) std::memcpy(out[0]->data.data() + at, t->data.data(), t->data.size() * sizeof(float));
        at += t->data.size();
    }
}

void gpu(const GpuOpArgs& a) {
    rt::BufferView dst = a.out[0].view;
    for (const GpuTensor& t : a.in) {
        const VkDeviceSize bytes = VkDeviceSize(numel(t.shape)) * 4;
        if (bytes == 0) continue;
        a.seq.copy(t.view, rt::BufferView{dst.buffer, dst.offset, bytes});
        dst.offset += bytes;
    }
}

}  // namespace

const OpDef op_stack{"stack", infer, cpu, gpu, 0, {}};

}  // namespace vtloc::ops
