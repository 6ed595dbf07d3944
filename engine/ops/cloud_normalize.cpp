// cloud_normalize: SPEC 1's normalised frame on the GPU -> shaders/cloud_normalize.comp.
// Input: cloud [N, D >= 3] (xyz first). Outputs: [N, D] with xyz mapped to
// (xyz - centre) / scale and the other columns copied (normals are not scaled),
// and the frame [4] = (centre xyz, scale). centre = mean(xyz), scale = max ||p - centre||.
// The model does NOT use this op: object_frame.h normalises on the host in
// double and rounds once, exactly as the PyTorch reference does, because FPS and
// ball query must see bit-equal coordinates to pick the same indices, and an
// fp32 reduction (any summation order) differs in the last bits. This op is
// for clouds already on the device where that bit-exactness does not matter.
#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/object_frame.h"
#include "engine/ops/ops.h"
#include "engine/ops/point_common.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    expect_input_count(in, 1, 1);
    expect_f32(in);
    const Shape& s = in[0].shape;
    if (s.size() != 2 || s[1] < 3) throw Error("cloud must be [N, D >= 3], got " + shape_str(s));
    if (s[0] == 0) throw Error("the point cloud is empty");
    to_u32(numel(s), "cloud size");
    return {TensorDesc{s}, TensorDesc{{4}}};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    const HostTensor& x = *in[0];
    require_finite_xyz(x, "cloud_normalize");
    // The oracle is the host normalisation the model itself uses (double, one rounding).
    const ObjectFrame f = object_frame(x, "cloud_normalize");
    *out[0] = to_frame(x, f, x.shape[1]);
    const double* c = f.centre.data();
    const double scale = f.scale;
    for (int k = 0; k < 3; ++k) out[1]->data[size_t(k)] = float(c[k]);
    out[1]->data[3] = float(scale);
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t cap = std::min({256u, d.max_invocations, d.max_workgroup_size[0], d.max_shared_memory / 16});
    uint32_t L = 1;
    while (L * 2 <= cap) L *= 2;
    struct { uint32_t N, D; } push{uint32_t(a.in[0].shape[0]), uint32_t(a.in[0].shape[1])};
    a.seq.dispatch(pipeline(a.ctx, "cloud_normalize", 3, sizeof(push), {L}),
                   {{a.in[0].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write},
                    {a.out[1].view, rt::Access::Write}},
                   &push, sizeof(push), 1);
}

}  // namespace

const OpDef op_cloud_normalize{"cloud_normalize", infer, cpu, gpu, 0, {}};

}  // namespace vtloc::ops
