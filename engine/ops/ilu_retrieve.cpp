// ilu_retrieve: the ILU head then retrieve (top-K and heat-map) on its contact,
// as one op, so that where the ILU takes its register-resident shader and
// retrieve its one-subgroup shader they run as one dispatch:
// shaders/ilu_retrieve.comp. Why: on lavapipe a dispatch and the barrier before
// it cost more than the retrieval's work, which as a node of its own was slower
// than its CPU reference; as the ILU's epilogue it adds only the work. Elsewhere
// (symmetry maps, K > 16, no shuffles, a forced ILU width below a subgroup, the
// loop budget, too few storage buffers) or with param fuse = 0, it records the
// two ops' own dispatches. Its CPU reference is theirs, one after the other.
// Inputs: the ILU's 13 (ilu.cpp), then candidates [M, 3], cloud [P, D >= 3] and
// optionally the symmetry maps [T, 12]. Params: the ILU's, and k.
// Outputs: c, contact (ilu), then index, score, heat-map, workspace (retrieve).
#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ilu_math.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

constexpr size_t kIluInputs = 13;

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, kIluInputs + 2, kIluInputs + 3);
    std::vector<TensorDesc> out = op_ilu.infer({in.begin(), in.begin() + kIluInputs}, p);
    std::vector<TensorDesc> ret_in{out[1]};
    ret_in.insert(ret_in.end(), in.begin() + kIluInputs, in.end());
    for (const TensorDesc& d : op_retrieve.infer(ret_in, p)) out.push_back(d);
    return out;
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    op_ilu.cpu({in.begin(), in.begin() + kIluInputs}, {out[0], out[1]}, p);
    std::vector<const HostTensor*> ret_in{out[1]};
    ret_in.insert(ret_in.end(), in.begin() + kIluInputs, in.end());
    op_retrieve.cpu(ret_in, {out.begin() + 2, out.end()}, p);
}

void gpu(const GpuOpArgs& a) {
    const std::vector<GpuTensor> ilu_in(a.in.begin(), a.in.begin() + kIluInputs), ilu_out{a.out[0], a.out[1]};
    std::vector<GpuTensor> ret_in{a.out[1]};
    ret_in.insert(ret_in.end(), a.in.begin() + kIluInputs, a.in.end());
    const std::vector<GpuTensor> ret_out(a.out.begin() + 2, a.out.end());
    const GpuOpArgs ilu{a.ctx, a.seq, ilu_in, ilu_out, a.params}, ret{a.ctx, a.seq, ret_in, ret_out, a.params};

    const rt::DeviceInfo& d = a.ctx.info();
    const ilu_math::Launch l = ilu_math::launch(ilu);
    const uint32_t storage_buffers = 15;  // ilu_retrieve.comp: 22 bindings, 7 of them texel buffers
    // One invocation runs the ILU, then both scans: lavapipe's loop limiter counts them together.
    if (a.params.get("fuse", 1) != 0 && l.wave && l.wave_L % std::max(1u, d.subgroup_size) == 0 &&
        storage_buffers <= d.max_storage_buffers && retrieve_fits_subgroup(ret, l.wave_loops)) {
        std::vector<rt::Binding> b = ilu_math::wave_bindings(ilu);
        for (const rt::Binding& r : retrieve_subgroup_bindings(ret)) b.push_back(r);  // from binding 15
        const int64_t P = ret_in[2].shape[0], D = ret_in[2].shape[1], M = ret_in[1].shape[0], K = a.out[2].shape.back();
        struct { uint32_t max_iters, P, D, M, K, T; } push{uint32_t(a.params.get("max_iters", 0)), uint32_t(P),
                                                           uint32_t(D), uint32_t(M), uint32_t(K), 0u};
        const uint32_t rows = to_u32(numel(a.in[0].shape) / a.in[0].shape.back(), "ILU batch");
        rt::PipelineDesc desc{"ilu_retrieve", 22, sizeof(push), {l.wave_L, l.C, l.H, l.RB, l.HB, uint32_t(K)},
                              ilu_math::kWaveTexels | kRetrieveSubgroupTexels << 15};
        a.seq.dispatch(a.ctx.pipelines().get(desc), b, &push, sizeof(push), rows);
        return;
    }
    op_ilu.gpu(ilu);
    op_retrieve.gpu(ret);
}

}  // namespace

const OpDef op_ilu_retrieve{"ilu_retrieve", infer, cpu, gpu, 1u << 5,
                            {"max_iters", "lanes", "subgroup", "wave", "k", "fuse"}};

}  // namespace vtloc::ops
