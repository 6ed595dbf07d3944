// linear: y = act(x W^T + b), W stored [N, K] as PyTorch does; x [..., K] is
// flattened to M rows. -> shaders/linear_subgroup.comp (weights passed between
// lanes by subgroup shuffles) where the device has shuffles and K % 4 == 0,
// else shaders/gemm.comp (shared-memory tiles). Both fuse bias + activation.
// Params: act (see Act, default none), slope (leaky, default 0.01), subgroup
// (default 1; 0 forces gemm.comp).
#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/gemm_tiles.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {

GemmTiles choose_gemm_tiles(const rt::DeviceInfo& d, int64_t M, int64_t N) {
    static const GemmTiles kSmallM[] = {{16, 64, 16, 1, 4}, {8, 32, 16, 1, 2}, {4, 16, 8, 1, 2}};
    static const GemmTiles kGeneral[] = {{64, 64, 16, 4, 4}, {32, 64, 16, 4, 4}, {32, 32, 16, 4, 4},
                                         {16, 32, 16, 2, 4}, {16, 16, 8, 2, 2}, {8, 8, 8, 2, 2},
                                         {4, 4, 4, 2, 2}};
    auto fits = [&](const GemmTiles& t) {
        return t.threads() <= d.max_invocations && t.threads() <= d.max_workgroup_size[0] &&
               t.shared_bytes() <= d.max_shared_memory;
    };
    const bool small_m = M <= 16 && N >= 32;
    for (int pass = 0; pass < 2; ++pass) {  // pass 0 also wants whole subgroups
        auto ok = [&](const GemmTiles& t) {
            return fits(t) && (pass == 1 || t.threads() % d.subgroup_size == 0);
        };
        if (small_m)
            for (const GemmTiles& t : kSmallM) if (ok(t)) return t;
        for (const GemmTiles& t : kGeneral) if (ok(t)) return t;
    }
    throw Error("device '" + d.name + "' cannot run even a 4x4 GEMM tile");
}

namespace {

// The shuffle shader: the device has subgroup shuffles, K splits into vec4s,
// x and W fit the texel limit and K is not so long that one thread's loop
// exceeds the loop budget.
bool use_subgroup_rows(const GpuOpArgs& a, int64_t M, int64_t N, int64_t K) {
    const rt::DeviceInfo& d = a.ctx.info();
    // Loop iterations of one thread: K / 4 blocks of up to 8 outputs (kLoopIterationBudget).
    return shuffles_allowed(a) && K % 4 == 0 && K > 0 &&
           uint64_t(M * K / 4) <= d.max_texel_elements && uint64_t(N * K / 4) <= d.max_texel_elements &&
           uint64_t(K / 4) * 9 + 16 <= kLoopIterationBudget;
}

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    expect_input_count(in, 2, 3);
    expect_f32(in);
    const Shape& x = in[0].shape;
    const Shape& w = in[1].shape;
    if (x.empty()) throw Error("input must have at least one dimension");
    if (w.size() != 2) throw Error("weight must be [out, in], got " + shape_str(w));
    if (x.back() != w[1])
        throw Error("input " + shape_str(x) + " has " + std::to_string(x.back()) +
                    " features but weight " + shape_str(w) + " expects " + std::to_string(w[1]));
    if (in.size() == 3 && in[2].shape != Shape{w[0]})
        throw Error("bias " + shape_str(in[2].shape) + " does not match weight " + shape_str(w));
    Shape y = x;
    y.back() = w[0];
    return {y};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const HostTensor& x = *in[0];
    const HostTensor& w = *in[1];
    const int64_t K = w.shape[1], N = w.shape[0];
    const int64_t M = N ? out[0]->size() / N : 0;
    const uint32_t act = uint32_t(p.get("act", kActNone));
    const float slope = float(p.get("slope", 0.01));
    for (int64_t m = 0; m < M; ++m)
        for (int64_t n = 0; n < N; ++n) {
            double acc = in.size() == 3 ? in[2]->data[size_t(n)] : 0.0;
            for (int64_t k = 0; k < K; ++k) acc += double(x.data[size_t(m * K + k)]) * w.data[size_t(n * K + k)];
            out[0]->data[size_t(m * N + n)] = apply_act(float(acc), act, slope);
        }
}

void gpu(const GpuOpArgs& a) {
    const Shape& ws = a.in[1].shape;
    const int64_t K = ws[1], N = ws[0];
    const int64_t M = numel(a.out[0].shape) / std::max<int64_t>(1, N);
    const rt::DeviceInfo& d = a.ctx.info();
    struct { uint32_t M, N, K, has_bias, act; float slope; } push{
        to_u32(M, "GEMM rows"), to_u32(N, "GEMM columns"), to_u32(K, "GEMM depth"),
        a.in.size() == 3 ? 1u : 0u, uint32_t(a.params.get("act", kActNone)), float(a.params.get("slope", 0.01))};
    to_u32(M * K, "GEMM input size");
    to_u32(M * N, "GEMM output size");
    // Without a bias any read-only buffer fills the binding; the shader skips it.
    const rt::BufferView& bias = a.in.size() == 3 ? a.in[2].view : a.in[1].view;
    if (M > 0 && N > 0 && use_subgroup_rows(a, M, N, K)) {
        uint32_t TN = std::min(8u, d.subgroup_size);
        // Whole subgroups, no more than the rows need: spare lanes redo the last row,
        // which a one-row layer would otherwise pay for 64 times per block.
        uint32_t local = subgroup_group_size(d);
        const uint32_t sg = std::max(1u, d.subgroup_size);
        while (local / 2 >= uint64_t(M) && (local / 2) % sg == 0) local /= 2;
        // GPUs: few rows (GMA's decoder, the point head) must still give every compute unit
        // work (rt::fill_workgroups): one subgroup a workgroup, then fewer outputs a block.
        // Param fill (tests): that many workgroups, on any device.
        const int64_t fill = int64_t(a.params.get("fill", 0));
        if (fill > 0 || d.type != VK_PHYSICAL_DEVICE_TYPE_CPU) {
            const uint64_t want = fill > 0 ? uint64_t(fill) : rt::fill_workgroups(d);
            auto groups = [&] { return (uint64_t(M) + local - 1) / local * ((uint64_t(N) + TN - 1) / TN); };
            while (groups() < want) {
                if (local / 2 >= sg && (local / 2) % sg == 0) local /= 2;
                else if (TN > 1) TN /= 2;
                else break;
            }
        }
        const uint64_t gx = (uint64_t(M) + local - 1) / local, gy = (uint64_t(N) + TN - 1) / TN;
        if (gx > d.max_workgroup_count[0] || gy > d.max_workgroup_count[1])
            throw Error("linear of " + std::to_string(M) + " rows and " + std::to_string(N) +
                        " outputs needs more workgroups than the device allows");
        const VkFormat v4 = VK_FORMAT_R32G32B32A32_SFLOAT;
        a.seq.dispatch(a.ctx.pipelines().get(rt::PipelineDesc{"linear_subgroup", 4, 24, {local, TN}, 0x3u}),
                       {{a.in[0].view, rt::Access::Read, v4}, {a.in[1].view, rt::Access::Read, v4},
                        {bias, rt::Access::Read}, {a.out[0].view, rt::Access::Write}},
                       &push, sizeof(push), uint32_t(gx), uint32_t(gy));
        return;
    }
    GemmTiles t = choose_gemm_tiles(d, M, N);
    const rt::Pipeline& pipe = pipeline(a.ctx, "gemm", 4, 24, {t.threads(), t.bm, t.bn, t.bk, t.tm, t.tn});
    a.seq.dispatch(pipe,
                   {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read},
                    {bias, rt::Access::Read}, {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), uint32_t((N + t.bn - 1) / t.bn), uint32_t((M + t.bm - 1) / t.bm));
}

}  // namespace

const OpDef op_linear{"linear", infer, cpu, gpu, 0, {"act", "slope", "subgroup", "fill"}};

}  // namespace vtloc::ops
