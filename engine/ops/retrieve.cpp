// retrieve: topk then heatmap (SPEC 3) as one op, so that where both take their
// one-subgroup shaders they run as one dispatch: shaders/retrieve_subgroup.comp
// (K <= 16, no symmetry maps, a device with shuffles, both scans within the loop
// budget). Elsewhere, or with param subgroup = 0, it records the two ops' own
// dispatches. Its CPU reference is theirs, one after the other.
// Inputs: contact [3] or a batch [B, 3], candidates [M, 3], cloud [P, D >= 3],
// optionally the symmetry maps [T, 12]. Param k. Outputs: the top-K index I32 and
// score ([K] or [B, K]), the heat-map ([P] or [B, P]), and topk's workspace.
#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 3, 4);
    std::vector<TensorDesc> top = op_topk.infer({in[0], in[1]}, p);
    std::vector<TensorDesc> heat_in{in[2], in[1], top[0]};
    if (in.size() == 4) heat_in.push_back(in[3]);
    std::vector<TensorDesc> heat = op_heatmap.infer(heat_in, p);
    return {top[0], top[1], heat[0], top[2]};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    op_topk.cpu({in[0], in[1]}, {out[0], out[1], out[3]}, p);
    std::vector<const HostTensor*> heat_in{in[2], in[1], out[0]};
    if (in.size() == 4) heat_in.push_back(in[3]);
    op_heatmap.cpu(heat_in, {out[2]}, p);
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const int64_t B = a.in[0].shape.size() == 2 ? a.in[0].shape[0] : 1;
    if (retrieve_fits_subgroup(a, 0) && B <= int64_t(d.max_workgroup_count[1])) {
        const int64_t P = a.in[2].shape[0], D = a.in[2].shape[1], M = a.in[1].shape[0], K = a.out[0].shape.back();
        struct { uint32_t P, D, M, K, T; } push{uint32_t(P), uint32_t(D), uint32_t(M), uint32_t(K), 0u};
        std::vector<rt::Binding> b = retrieve_subgroup_bindings(a);
        b.push_back({a.in[0].view, rt::Access::Read});  // the contacts, binding 7
        const uint32_t sg = std::max(1u, d.subgroup_size);
        a.seq.dispatch(a.ctx.pipelines().get(rt::PipelineDesc{"retrieve_subgroup", 8, 20, {sg, uint32_t(K)},
                                                              kRetrieveSubgroupTexels}),
                       b, &push, sizeof(push), 1, uint32_t(B));
        return;
    }
    op_topk.gpu({a.ctx, a.seq, {a.in[0], a.in[1]}, {a.out[0], a.out[1], a.out[3]}, a.params});
    std::vector<GpuTensor> heat_in{a.in[2], a.in[1], a.out[0]};
    if (a.in.size() == 4) heat_in.push_back(a.in[3]);
    op_heatmap.gpu({a.ctx, a.seq, heat_in, {a.out[2]}, a.params});
}

}  // namespace

bool retrieve_fits_subgroup(const GpuOpArgs& a, uint64_t loops_before) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t sg = std::max(1u, d.subgroup_size);
    const int64_t M = a.in[1].shape[0], P = a.in[2].shape[0], D = a.in[2].shape[1], K = a.out[0].shape.back();
    // One invocation runs both scans, which share lavapipe's loop limiter.
    const uint64_t loops =
        loops_before + topk_subgroup_iterations(M, K, sg) + heatmap_subgroup_iterations(P, K, 0, sg);
    return shuffles_allowed(a) && a.in.size() == 3 && K <= 16 && loops <= kLoopIterationBudget &&
           uint64_t(M) * 3 <= d.max_texel_elements && uint64_t(P * D) <= d.max_texel_elements;
}

std::vector<rt::Binding> retrieve_subgroup_bindings(const GpuOpArgs& a) {
    const VkFormat r32 = VK_FORMAT_R32_SFLOAT;
    const rt::BufferView &cand = a.in[1].view, &cloud = a.in[2].view;
    return {{cloud, rt::Access::Read, r32}, {cand, rt::Access::Read},       {a.out[0].view, rt::Access::Write},
            {cand, rt::Access::Read},       {a.out[2].view, rt::Access::ReadWrite}, {cand, rt::Access::Read, r32},
            {a.out[1].view, rt::Access::Write}};
}

const OpDef op_retrieve{"retrieve", infer, cpu, gpu, 1u << 3, {"k", "subgroup"}};  // output 3: topk's workspace

}  // namespace vtloc::ops
