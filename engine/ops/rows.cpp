// rows: x [N, d1, ...] -> x[start : start + count] (params start, count), one
// buffer copy of the rows' byte range and no shader. The batched graph uses it
// to hand each touch its row of the batch's F^t and P^d.
#include <cmath>
#include <cstring>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

struct Range {
    int64_t start, count;
};

Range range(const Shape& x, const Params& p) {
    const double start = p.get("start", 0), count = p.get("count", 1);
    if (start != std::floor(start) || count != std::floor(count) || start < 0 || count < 1 ||
        start + count > double(x[0]))
        throw Error("rows [" + std::to_string(start) + ", +" + std::to_string(count) + ") are outside the " +
                    std::to_string(x[0]) + " rows of " + shape_str(x));
    return {int64_t(start), int64_t(count)};
}

int64_t row_elems(const Shape& x) { return x[0] ? numel(x) / x[0] : 0; }

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 1, 1);
    if (in[0].shape.empty()) throw Error("input must have a first axis, got a scalar");
    TensorDesc out = in[0];
    out.shape[0] = range(in[0].shape, p).count;
    return {out};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const Range r = range(in[0]->shape, p);
    const size_t row = size_t(row_elems(in[0]->shape));
    if (row) std::memcpy(out[0]->data.data(), in[0]->data.data() + size_t(r.start) * row, size_t(r.count) * row * sizeof(float));
}

void gpu(const GpuOpArgs& a) {
    const Range r = range(a.in[0].shape, a.params);
    const VkDeviceSize row = VkDeviceSize(row_elems(a.in[0].shape)) * 4;
    if (row == 0) return;
    const rt::BufferView& src = a.in[0].view;
    a.seq.copy(rt::BufferView{src.buffer, src.offset + VkDeviceSize(r.start) * row, VkDeviceSize(r.count) * row},
               a.out[0].view);
}

}  // namespace

const OpDef op_rows{"rows", infer, cpu, gpu, 0, {"start", "count"}};

}  // namespace vtloc::ops
