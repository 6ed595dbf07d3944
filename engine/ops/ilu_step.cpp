// ilu_step: one ILU iteration per dispatch -> shaders/ilu_step.comp. Not used by
// the model (the fused `ilu` is faster); the bench records the head this way to
// put a timestamp between iterations (engine/model/heads.h build_ilu_stepped).
// Inputs: the 13 of `ilu` (engine/ops/ilu_math.h), then the state of the
// previous step (step 0: any F32 tensor, not read).
// Params: max_iters (1..64), step (0..max_iters-1). Step k runs iteration k+1
// when k < N, else passes the state on.
// Outputs: state [4C + 3 + 3 max_iters] = [h | gx | c | c_1..c_max_iters],
// c [max_iters, 3] (rows after N zero) and contact [3] = c so far.
// The state is fp32 between steps (the fused op keeps h in fp32 too).
#include <cmath>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ilu_math.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

int64_t state_size(int64_t C, int64_t max_iters) { return 4 * C + 3 + 3 * max_iters; }

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 14, 14);
    const double max_iters = p.get("max_iters", -1), step = p.get("step", -1);
    if (!(max_iters >= 1 && max_iters <= 64) || max_iters != std::floor(max_iters))
        throw Error("max_iters must be an integer in 1..64, got " + std::to_string(max_iters));
    if (!(step >= 0 && step < max_iters) || step != std::floor(step))
        throw Error("step must be an integer in 0.." + std::to_string(int(max_iters) - 1) + ", got " +
                    std::to_string(step));
    const int64_t C = ilu_math::check_inputs(in), S = state_size(C, int64_t(max_iters));
    if (in[13].type != ElemType::F32 || (step > 0 && in[13].shape != Shape{S}))
        throw Error("the state of step " + std::to_string(int(step) - 1) + " must be F32 [" + std::to_string(S) +
                    "], got " + shape_str(in[13].shape));
    return {TensorDesc{{S}}, TensorDesc{{int64_t(max_iters), 3}}, TensorDesc{{3}}};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const int max_iters = int(p.get("max_iters", 0)), step = int(p.get("step", 0));
    const int n = in[2]->int_at(0);
    if (n < 0 || n > max_iters)
        throw Error("ILU iteration count " + std::to_string(n) + " is outside 0.." + std::to_string(max_iters));
    const size_t C = size_t(in[0]->shape.back()), at = 4 * C + 3;
    std::vector<float>& state = out[0]->data;
    std::fill(state.begin(), state.end(), 0.0f);
    ilu_math::State st;
    if (step > 0) {  // continue from the previous step's fp32 state, as the shader does
        const std::vector<float>& prev = in[13]->data;
        st.h.assign(prev.begin(), prev.begin() + long(C));
        st.gx.assign(prev.begin() + long(C), prev.begin() + long(4 * C));
        for (size_t j = 0; j < 3; ++j) st.c[j] = prev[4 * C + j];
        std::copy(prev.begin() + long(at), prev.begin() + long(at) + 3 * step, state.begin() + long(at));
    } else {
        st = ilu_math::init(in);
        for (size_t i = 0; i < 3 * C; ++i) st.gx[i] = float(st.gx[i]);  // the shader keeps gx in fp32
    }
    if (step < n) {
        ilu_math::iterate(in, st);
        for (size_t j = 0; j < 3; ++j) state[at + 3 * size_t(step) + j] = float(st.c[j]);
    }
    for (size_t i = 0; i < C; ++i) state[i] = float(st.h[i]);
    for (size_t i = 0; i < 3 * C; ++i) state[C + i] = float(st.gx[i]);
    for (size_t j = 0; j < 3; ++j) state[4 * C + j] = out[2]->data[j] = float(st.c[j]);
    std::copy(state.begin() + long(at), state.end(), out[1]->data.begin());
}

void gpu(const GpuOpArgs& a) {
    const ilu_math::Launch l = ilu_math::launch(a);
    const uint32_t push[2] = {uint32_t(a.params.get("max_iters", 0)), uint32_t(a.params.get("step", 0))};
    std::vector<rt::Binding> b;
    for (const GpuTensor& t : a.in) b.push_back({t.view, rt::Access::Read});
    for (const GpuTensor& t : a.out) b.push_back({t.view, rt::Access::Write});
    a.seq.dispatch(pipeline(a.ctx, l.subgroup ? "ilu_step_subgroup" : "ilu_step", 17, 8, {l.L, l.C, l.H, l.G}), b,
                   push, 8, 1);
}

}  // namespace

const OpDef op_ilu_step{"ilu_step", infer, cpu, gpu, 0, {"max_iters", "step", "lanes", "subgroup"}};

}  // namespace vtloc::ops
