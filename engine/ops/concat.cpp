// Concatenation along the last axis -> shaders/concat.comp (one dispatch per input),
// or for a single row (every input one slice of the output) one buffer copy per
// input: on lavapipe a copy is a memcpy, a dispatch costs ~70 us, and GMA's
// [F^t, F^p] of one touch is such a row.
#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    if (in.empty()) throw Error("takes at least one input");
    expect_f32(in);
    const Shape& first = in[0].shape;
    Shape out = first;
    if (out.empty()) throw Error("cannot concatenate scalars");
    out.back() = 0;
    for (const TensorDesc& d : in) {
        const Shape& s = d.shape;
        if (s.size() != first.size() || !std::equal(s.begin(), s.end() - 1, first.begin()))
            throw Error("shapes " + shape_str(first) + " and " + shape_str(s) +
                        " differ outside the last axis");
        out.back() += s.back();
    }
    return {out};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    const int64_t width = out[0]->shape.back();
    const int64_t rows = width ? out[0]->size() / width : 0;
    int64_t col0 = 0;
    for (const HostTensor* t : in) {
        int64_t w = t->shape.back();
        for (int64_t r = 0; r < rows; ++r)
            for (int64_t c = 0; c < w; ++c) out[0]->data[size_t(r * width + col0 + c)] = t->data[size_t(r * w + c)];
        col0 += w;
    }
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    uint32_t local = elementwise_local_size(d);
    const rt::Pipeline& pipe = pipeline(a.ctx, "concat", 2, 16, {local});
    const Shape& os = a.out[0].shape;
    uint32_t out_width = to_u32(os.back(), "concat width");
    uint32_t rows = out_width ? to_u32(numel(os) / os.back(), "concat rows") : 0;
    if (rows == 1) {
        VkDeviceSize at = a.out[0].view.offset;
        for (const GpuTensor& t : a.in) {
            a.seq.copy(t.view, {a.out[0].view.buffer, at, t.view.size});
            at += t.view.size;
        }
        return;
    }
    uint32_t col0 = 0;
    for (const GpuTensor& t : a.in) {
        struct { uint32_t rows, width, out_width, col0; } push{rows, to_u32(t.shape.back(), "width"), out_width, col0};
        // Inputs write disjoint columns but overlapping byte ranges: the tracker
        // orders them with a barrier, which is cheap next to a missed hazard.
        a.seq.dispatch(pipe, {{t.view, rt::Access::Read}, {a.out[0].view, rt::Access::Write}}, &push,
                       sizeof(push), grid_groups(uint64_t(rows) * push.width, local, d));
        col0 += push.width;
    }
}

}  // namespace

const OpDef op_concat{"concat", infer, cpu, gpu, 0, {}};

}  // namespace vtloc::ops
