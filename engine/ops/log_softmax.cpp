// log_softmax: a flat log score [M] -> its log probabilities and probabilities
// (the multi-touch filter's belief; double logsumexp on the CPU). -> shaders/log_softmax.comp
// (one workgroup: the filter normalises once per touch). A score of -inf or +inf
// everywhere is refused by the CPU reference; the GPU follows IEEE.
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

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t M = uint32_t(a.in[0].shape[0]);
    uint32_t local = elementwise_local_size(d);
    while (local > 1 && local * 4 > d.max_shared_memory) local /= 2;
    check_loop_budget(d, 3 * ((uint64_t(M) + local - 1) / local) + 16, "log_softmax");
    a.seq.dispatch(pipeline(a.ctx, "log_softmax", 3, 4, {local}),
                   {{a.in[0].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write},
                    {a.out[1].view, rt::Access::Write}},
                   &M, 4, 1);
}

}  // namespace

const OpDef op_log_softmax{"log_softmax", infer, cpu, gpu, 0, {}};

}  // namespace vtloc::ops
