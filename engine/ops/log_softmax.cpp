// log_softmax: a flat log score [M] -> its log probabilities and probabilities
// (the multi-touch filter's belief; double logsumexp on the CPU). -> shaders/log_softmax.glsl
// (chunks' max and sum of exps into scratch, then each chunk normalised; .comp reads the
// score as texels, _ssbo.comp past the texel limit). A score of -inf or +inf
// everywhere is refused by the CPU reference; the GPU follows IEEE.
#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    const double groups = p.get("groups", 0);
    if (!(groups >= 0 && groups <= 1024 && groups == std::floor(groups))) throw Error("log_softmax: groups must be 0..1024");
    expect_input_count(in, 1, 1);
    expect_f32(in);
    if (in[0].shape.size() != 1 || in[0].shape[0] == 0)
        throw Error("log_softmax needs a flat [M > 0] score, got " + shape_str(in[0].shape));
    to_u32(in[0].shape[0], "score size");
    return {TensorDesc{in[0].shape}, TensorDesc{in[0].shape}};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    const std::vector<float>& v = in[0]->data;
    for (float x : v)
        if (std::isnan(x) || x == INFINITY) throw Error("log_softmax: the score holds NaN or +inf");
    double m = *std::max_element(v.begin(), v.end()), s = 0;
    if (!std::isfinite(m)) throw Error("log_softmax: every score is -inf");
    for (float x : v) s += std::exp(double(x) - m);
    const double lse = m + std::log(s);
    for (size_t i = 0; i < v.size(); ++i) {
        out[0]->data[i] = float(double(v[i]) - lse);
        out[1]->data[i] = float(std::exp(double(v[i]) - lse));
    }
}

// The workgroups and each one's chunk: enough to fill the device (a CPU driver's
// threads, 4 per compute unit on a GPU; param groups (tests) asks for another number),
// each chunk at least one workgroup wide.
struct Split {
    uint32_t local, groups, chunk;
};
Split split_of(const rt::DeviceInfo& d, uint64_t M, const Params& p) {
    uint32_t local = elementwise_local_size(d);
    while (local > 1 && local * 4 > d.max_shared_memory) local /= 2;
    const uint64_t asked = uint64_t(p.get("groups", 0));  // 0..1024 (infer checks)
    const uint64_t fill = asked > 0 ? asked : rt::fill_workgroups(d);
    const uint64_t most = std::min<uint64_t>({fill, (M + local - 1) / local, 1024});
    const uint32_t chunk = uint32_t((M + most - 1) / most);
    return {local, uint32_t((M + chunk - 1) / chunk), chunk};
}

uint64_t scratch_bytes(const rt::DeviceInfo& d, const std::vector<Shape>& in, const Params& p) {
    return 8ull * split_of(d, uint64_t(in.at(0).at(0)), p).groups;
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t M = uint32_t(a.in[0].shape[0]);
    const Split sp = split_of(d, M, a.params);
    check_loop_budget(d, (uint64_t(sp.chunk) + sp.local - 1) / sp.local * 2 + sp.groups * 2 + 16, "log_softmax");
    if (a.scratch.size < 8ull * sp.groups)
        throw Error("log_softmax: its scratch is smaller than its " + std::to_string(sp.groups) + " parts need");
    // The score as a texel buffer where the device allows (a gather on a CPU driver).
    const bool texel = texels_allowed(a, {M});
    const struct { uint32_t M, C, G; } push{M, sp.chunk, sp.groups};
    const rt::BufferView part{a.scratch.buffer, a.scratch.offset, 8ull * sp.groups};
    const rt::Access R = rt::Access::Read, W = rt::Access::Write;
    const VkFormat vf = texel ? VK_FORMAT_R32_SFLOAT : VK_FORMAT_UNDEFINED;
    for (uint32_t pass : {0u, 1u})
        a.seq.dispatch(a.ctx.pipelines().get(rt::PipelineDesc{texel ? "log_softmax" : "log_softmax_ssbo", 4,
                                                              uint32_t(sizeof(push)), {sp.local, pass}, texel ? 1u : 0u}),
                       {{a.in[0].view, R, vf}, {a.out[0].view, W}, {a.out[1].view, W}, {part, pass ? R : W}},
                       &push, sizeof(push), sp.groups);
}

}  // namespace

const OpDef op_log_softmax{"log_softmax", infer, cpu, gpu, 0, {"texel", "groups"}, nullptr, scratch_bytes};

}  // namespace vtloc::ops
