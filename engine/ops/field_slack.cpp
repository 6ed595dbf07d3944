// field_slack: log fields over the filter's hypotheses [F, S * NS] widened by
// odometry slack (docs/multitouch.md, "Under odometry noise, the fields widened"): each
// value becomes the best, within the neighbourhood, of the field less a Gaussian
// log-prior of the offset. Inputs: fields [F, S * NS]; neighbours [S, KN, 3], per
// sample its neighbours s' (as floats, -1 after the last; an entry out of range
// ends the row too), their squared distance
// d^2 and the spin offset off (0..NS-1) that keeps a pose's heading from s to s';
// widths [F, 2], per field a_t = 1 / (2 sigma_t^2) and a_r = 1 / (2 sigma_r^2)
// (0: no slack of that kind). Param n_spin. Out[f, s NS + j] = max of in at (s, j),
// at (s, j +- 1) less a_r step^2 (step = 2 pi / NS), and at (s', j + off) less a_t d^2.
// -> shaders/field_slack.comp
#include <cfloat>
#include <cmath>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"
#include "engine/ops/point_common.h"

namespace vtloc::ops {
namespace {

int64_t slack_spins(const Params& p) { return int_param(p, "n_spin", 1, 65536); }

// The spin step squared, as both paths compute it (one float expression).
float step2_of(int64_t NS) {
    const float step = float(2 * M_PI / double(NS));
    return step * step;
}

// Below the smallest normal float: 0, on both paths (a GPU may flush subnormals; lavapipe does).
float normal_or_zero(float x) { return x >= FLT_MIN ? x : 0.0f; }

std::vector<TensorDesc> slack_infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 3, 3);
    expect_f32(in);
    const int64_t NS = slack_spins(p);
    const Shape &f = in[0].shape, &nb = in[1].shape, &w = in[2].shape;
    if (nb.size() != 3 || nb[0] == 0 || nb[1] == 0 || nb[2] != 3)
        throw Error("neighbours must be [S > 0, KN > 0, 3], got " + shape_str(nb));
    const int64_t S = nb[0];
    if (f.size() != 2 || f[0] == 0 || f[1] != S * NS)
        throw Error("fields must be [F > 0, S * NS] = [F, " + std::to_string(S * NS) + "], got " + shape_str(f));
    if (w != Shape{f[0], 2}) throw Error("widths must be [F, 2] = " + shape_str({f[0], 2}) + ", got " + shape_str(w));
    to_u32(f[0] * f[1], "field array size");
    to_u32(3 * S * nb[1], "neighbour table size");
    return {TensorDesc{f}};
}

void slack_cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const int64_t NS = slack_spins(p), S = in[1]->shape[0], KN = in[1]->shape[1], F = in[0]->shape[0], H = S * NS;
    const float step2 = step2_of(NS);
    const std::vector<float>&fin = in[0]->data, &nb = in[1]->data, &w = in[2]->data;
    std::vector<float>& fout = out[0]->data;
    for (int64_t f = 0; f < F; ++f) {
        const float at = normal_or_zero(w[size_t(2 * f)]), ar = normal_or_zero(w[size_t(2 * f + 1)]);
        const float* x = &fin[size_t(f * H)];
        for (int64_t s = 0; s < S; ++s)
            for (int64_t j = 0; j < NS; ++j) {
                float v = x[s * NS + j];
                if (ar > 0 && NS > 1) {
                    const float pen = ar * step2;
                    v = std::max(v, x[s * NS + (j + 1) % NS] - pen);
                    v = std::max(v, x[s * NS + (j + NS - 1) % NS] - pen);
                }
                if (at > 0)
                    for (int64_t k = 0; k < KN; ++k) {
                        const float* r = &nb[size_t((s * KN + k) * 3)];
                        if (!(r[0] >= 0 && r[0] < 4294967296.0f && int64_t(r[0]) < S && r[2] >= 0 && r[2] < float(NS) && r[1] >= 0)) break;
                        const float pen = r[1] >= FLT_MIN ? at * r[1] : 0.0f;  // at = inf, d^2 = 0 would be NaN
                        v = std::max(v, x[int64_t(r[0]) * NS + (j + int64_t(r[2])) % NS] - pen);
                    }
                fout[size_t(f * H + s * NS + j)] = v;
            }
    }
}

void slack_gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const int64_t NS = slack_spins(a.params);
    struct { uint32_t F, S, NS, KN; float step2; } push{uint32_t(a.in[0].shape[0]), uint32_t(a.in[1].shape[0]), uint32_t(NS),
                                                         uint32_t(a.in[1].shape[1]), step2_of(NS)};
    const uint64_t total = uint64_t(push.F) * push.S * push.NS;
    const uint32_t local = elementwise_local_size(d), groups = grid_groups(total, local, d);
    const uint64_t strides = (total + uint64_t(groups) * local - 1) / (uint64_t(groups) * local);
    check_loop_budget(d, strides * (uint64_t(push.KN) + 3), "field_slack");
    a.seq.dispatch(pipeline(a.ctx, "field_slack", 4, sizeof(push), {local}),
                   {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read}, {a.in[2].view, rt::Access::Read},
                    {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), groups);
}

}  // namespace

const OpDef op_field_slack{"field_slack", slack_infer, slack_cpu, slack_gpu, 0, {"n_spin"}};

}  // namespace vtloc::ops
