// gma_decode: the GMA decoder's output transform on rows of 6 ->
// shaders/gma_decode.comp: xyz = tanh(o[0:3]), n = o[3:6] / max(||o[3:6]||, 1e-6)
// (SPEC 2), so P^d has coordinates in (-1, 1) and unit normals.
#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    expect_input_count(in, 1, 1);
    expect_f32(in);
    if (in[0].shape.empty() || in[0].shape.back() != 6)
        throw Error("input must be [..., 6] (xyz and normal), got " + shape_str(in[0].shape));
    return {in[0]};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    const float* o = in[0]->data.data();
    float* y = out[0]->data.data();
    for (int64_t r = 0; r < in[0]->size() / 6; ++r, o += 6, y += 6) {
        for (int i = 0; i < 3; ++i) y[i] = std::tanh(o[i]);
        double norm = std::sqrt(double(o[3]) * o[3] + double(o[4]) * o[4] + double(o[5]) * o[5]);
        double scale = 1.0 / std::max(norm, 1e-6);
        for (int i = 3; i < 6; ++i) y[i] = float(o[i] * scale);
    }
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t local = elementwise_local_size(d);
    uint32_t rows = to_u32(numel(a.in[0].shape) / 6, "rows");
    if (rows == 0) return;
    a.seq.dispatch(pipeline(a.ctx, "gma_decode", 2, 4, {local}),
                   {{a.in[0].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write}}, &rows, 4,
                   grid_groups(rows, local, d));
}

}  // namespace

const OpDef op_gma_decode{"gma_decode", infer, cpu, gpu, 0, {}};

}  // namespace vtloc::ops
