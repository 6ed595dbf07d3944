// ilu: the whole ILU head (SPEC 2) fused -> shaders/ilu.comp, one dispatch, one
// workgroup (h is only C wide, so the iterations are latency-bound: keeping h and
// the gates in shared memory beats 10+ dispatches per iteration).
// Inputs: ft [1, C] or [B, C] (B touches: one workgroup each, all with the one
//   F^p), fp [1, C], iters I32 [1] (N, read at run time),
//   convz.weight [C, 3C], convz.bias [C], convr.*, convq.*, head.0.weight [H, C],
//   head.0.bias [H], head.2.weight [3, H], head.2.bias [3].
// Param max_iters (0..64): outputs c [max_iters, 3] = c_1..c_N then zero rows,
// and contact [3] = c_N (0 for N = 0); for ft [B, C] with B > 1, c [B, max_iters, 3]
// and contact [B, 3]. N outside 0..max_iters is an error here;
// the shader clamps it (the host checks N before a run, see engine/model/heads.h).
#include <cmath>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ilu_math.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

constexpr int kMaxIters = 64;

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 13, 13);
    const double max_iters = p.get("max_iters", -1);
    if (!(max_iters >= 0 && max_iters <= kMaxIters) || max_iters != std::floor(max_iters))
        throw Error("max_iters must be an integer in 0..64, got " + std::to_string(max_iters));
    const int64_t C = ilu_math::check_inputs(in, true), B = numel(in[0].shape) / C;
    if (B == 1) return {TensorDesc{{int64_t(max_iters), 3}}, TensorDesc{{3}}};
    return {TensorDesc{{B, int64_t(max_iters), 3}}, TensorDesc{{B, 3}}};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const int max_iters = int(p.get("max_iters", 0));
    const int n = in[2]->int_at(0);
    if (n < 0 || n > max_iters)
        throw Error("ILU iteration count " + std::to_string(n) + " is outside 0.." + std::to_string(max_iters));
    std::fill(out[0]->data.begin(), out[0]->data.end(), 0.0f);
    const int64_t B = numel(in[0]->shape) / in[0]->shape.back();
    for (int64_t b = 0; b < B; ++b) {
        ilu_math::State st = ilu_math::init(in, b);
        float* cs = out[0]->data.data() + size_t(b * max_iters * 3);
        for (int it = 0; it < n; ++it) {
            ilu_math::iterate(in, st);
            for (int j = 0; j < 3; ++j) cs[it * 3 + j] = float(st.c[j]);
        }
        for (int j = 0; j < 3; ++j) out[1]->data[size_t(b * 3 + j)] = float(st.c[j]);
    }
}

void gpu(const GpuOpArgs& a) {
    const ilu_math::Launch l = ilu_math::launch(a);
    uint32_t max_iters = uint32_t(a.params.get("max_iters", 0));
    const uint32_t rows = to_u32(numel(a.in[0].shape) / a.in[0].shape.back(), "ILU batch");
    if (l.wave) {
        rt::PipelineDesc desc{"ilu_wave", 15, 4, {l.wave_L, l.C, l.H, l.RB, l.HB}, ilu_math::kWaveTexels};
        a.seq.dispatch(a.ctx.pipelines().get(desc), ilu_math::wave_bindings(a), &max_iters, 4, rows);
        return;
    }
    std::vector<rt::Binding> b;
    for (const GpuTensor& t : a.in) b.push_back({t.view, rt::Access::Read});
    for (const GpuTensor& t : a.out) b.push_back({t.view, rt::Access::Write});
    a.seq.dispatch(pipeline(a.ctx, l.subgroup ? "ilu_subgroup" : "ilu", 15, 4, {l.L, l.C, l.H, l.G}), b, &max_iters, 4,
                   rows);
}

}  // namespace

const OpDef op_ilu{"ilu", infer, cpu, gpu, 0, {"max_iters", "lanes", "subgroup", "wave"}};

}  // namespace vtloc::ops
