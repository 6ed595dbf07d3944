// Concatenation along the last axis -> shaders/concat.comp (one dispatch per input),
// or for a single row (every input one slice of the output) one buffer copy per
// input: on lavapipe a copy is a memcpy, a dispatch costs ~70 us, and GMA's
// [F^t, F^p] of one touch is such a row.
#include <algorithm>

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
        const uint32_t width = to_u32(t.shape.back(), "width");
        const bool vec4 = width % 4 == 0 && out_width % 4 == 0 && col0 % 4 == 0;
        const uint32_t cols = vec4 ? width / 4 : width;  // invocations along x
        // A row's columns in whole subgroups; rows along y, at most 256 workgroups
        // of them (each loops over rows): a CPU driver pays per workgroup.
        const uint32_t local = row_span_local_size(d, cols);
        const uint32_t gx = (cols + local - 1) / local;
        const uint32_t gy = std::min({rows, 256u, d.max_workgroup_count[1]});
        if (gx > d.max_workgroup_count[0])
            throw Error("a concat input of width " + std::to_string(width) + " needs more workgroups than the device allows");
        struct { uint32_t rows, width, out_width, col0; } push{rows, width, out_width, col0};
        // Inputs write disjoint columns but overlapping byte ranges: the tracker
        // orders them with a barrier, which is cheap next to a missed hazard.
        const rt::Access R = rt::Access::Read, W = rt::Access::Write;
        a.seq.dispatch(pipeline(a.ctx, "concat", 4, 16, {local, vec4}),
                       {{t.view, R}, {t.view, R}, {a.out[0].view, W}, {a.out[0].view, W}}, &push, sizeof(push),
                       std::max(1u, gx), std::max(1u, gy));
        col0 += width;
    }
}

}  // namespace

const OpDef op_concat{"concat", infer, cpu, gpu, 0, {}};

}  // namespace vtloc::ops
