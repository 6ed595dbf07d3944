// add / sub / mul of a and b, where b's shape equals a's or is a suffix of it
// (b repeats, as a bias does) -> shaders/binary.comp
#include <algorithm>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    expect_input_count(in, 2, 2);
    expect_f32(in);
    const Shape& a = in[0].shape;
    const Shape& b = in[1].shape;
    bool suffix = b.size() <= a.size() && std::equal(b.rbegin(), b.rend(), a.rbegin());
    if (!suffix || (numel(b) == 0 && numel(a) != 0))
        throw Error("shapes " + shape_str(a) + " and " + shape_str(b) +
                    " do not broadcast (the second must equal the first or its trailing dimensions)");
    return {a};
}

template <int OP>
void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    const auto& a = in[0]->data;
    const auto& b = in[1]->data;
    for (size_t i = 0; i < a.size(); ++i) {
        float y = b[i % b.size()];
        out[0]->data[i] = OP == 0 ? a[i] + y : OP == 1 ? a[i] * y : a[i] - y;
    }
}

template <int OP>
void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    uint32_t local = elementwise_local_size(d);
    const rt::Pipeline& pipe = pipeline(a.ctx, "binary", 3, 8, {local, uint32_t(OP)});
    struct { uint32_t n, nb; } push{to_u32(numel(a.in[0].shape), "tensor size"),
                                    std::max<uint32_t>(1, to_u32(numel(a.in[1].shape), "tensor size"))};
    a.seq.dispatch(pipe,
                   {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read},
                    {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), grid_groups(push.n, local, d));
}

}  // namespace

const OpDef op_add{"add", infer, cpu<0>, gpu<0>, 0, {}};
const OpDef op_mul{"mul", infer, cpu<1>, gpu<1>, 0, {}};
const OpDef op_sub{"sub", infer, cpu<2>, gpu<2>, 0, {}};

}  // namespace vtloc::ops
