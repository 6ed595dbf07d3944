// chamfer: mean_a min_b ||a - b||^2 + mean_b min_a ||a - b||^2 (SPEC 3) over rows
// of width 3 or 6 (the last axis; leading axes are flattened into rows).
// -> shaders/chamfer_nn_subgroup.comp (both nearest-neighbour searches, target
// rows passed by subgroup shuffles; chamfer_nn.comp tiles them through shared
// memory on devices without shuffles, or with param subgroup = 0) then
// shaders/chamfer_sum.comp (the means, one workgroup). Param queries (1..8, 0 =
// the device's choice) sets the shuffle shader's queries per thread.
// Outputs: 0 = the distance (a 0-d scalar), 1 = the per-row nearest squared
// distances [Na + Nb] (A's rows, then B's), which the second pass reduces.
#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

constexpr int kMaxQueries = 8;

// Targets one dispatch scans per query: within kLoopIterationBudget whatever the
// subgroup size (the shuffle shader adds one round per subgroup of targets).
constexpr uint32_t kTargetChunk = 32768;

int64_t rows_of(const Shape& s) { return numel(s) / s.back(); }
int64_t sets_of(const Shape& a) { return a.size() == 3 && a[0] > 1 ? a[0] : 1; }

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 2, 2);
    const double q = p.get("queries", 0);
    if (q != std::floor(q) || q < 0 || q > kMaxQueries)
        throw Error("queries per thread must be 0 (the device's choice) to " + std::to_string(kMaxQueries) + ", got " +
                    std::to_string(q));
    expect_f32(in);
    for (size_t i = 0; i < 2; ++i) {
        const Shape& s = in[i].shape;
        if (s.empty() || (s.back() != 3 && s.back() != 6))
            throw Error(std::string("point set ") + (i ? "B " : "A ") + shape_str(s) + " must have rows of width 3 or 6");
        if (rows_of(s) == 0) throw Error(std::string("point set ") + (i ? "B" : "A") + " is empty");
    }
    if (in[0].shape.back() != in[1].shape.back())
        throw Error("point sets have rows of different widths: " + shape_str(in[0].shape) + " and " +
                    shape_str(in[1].shape));
    const int64_t sets = sets_of(in[0].shape);
    return {TensorDesc{sets > 1 ? Shape{sets} : Shape{}},
            TensorDesc{Shape{rows_of(in[0].shape) + sets * rows_of(in[1].shape)}}};
}

// min over the n rows of `to` of the squared distance to row `from`, in double.
double nearest(const float* from, const float* to, int64_t n, int64_t D) {
    double best = std::numeric_limits<double>::infinity();
    for (int64_t j = 0; j < n; ++j) {
        double d = 0.0;
        for (int64_t c = 0; c < D; ++c) {
            double e = double(from[c]) - to[j * D + c];
            d += e * e;
        }
        best = std::min(best, d);
    }
    return best;
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    const HostTensor &a = *in[0], &b = *in[1];
    for (int i = 0; i < 2; ++i)
        for (float v : in[size_t(i)]->data)
            if (!std::isfinite(v)) throw Error(std::string("chamfer: point set ") + (i ? "B" : "A") + " holds NaN or inf");
    const int64_t sets = sets_of(a.shape), D = a.shape.back(), Na = a.size() / D / sets, Nb = b.size() / D;
    for (int64_t s = 0; s < sets; ++s) {
        const float* as = &a.data[size_t(s * Na * D)];
        float* mins = &out[1]->data[size_t(s * (Na + Nb))];
        double sa = 0.0, sb = 0.0;
        for (int64_t q = 0; q < Na; ++q) {
            double d = nearest(as + q * D, b.data.data(), Nb, D);
            mins[q] = float(d);
            sa += d;
        }
        for (int64_t q = 0; q < Nb; ++q) {
            double d = nearest(&b.data[size_t(q * D)], as, Na, D);
            mins[Na + q] = float(d);
            sb += d;
        }
        out[0]->data[size_t(s)] = float(sa / double(Na) + sb / double(Nb));
    }
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t D = uint32_t(a.in[0].shape.back());
    const uint32_t sets = to_u32(sets_of(a.in[0].shape), "point sets");
    const uint32_t Na = to_u32(rows_of(a.in[0].shape) / sets, "rows of A");
    const uint32_t Nb = to_u32(rows_of(a.in[1].shape), "rows of B");
    if (sets > d.max_workgroup_count[1])
        throw Error(std::to_string(sets) + " point sets exceed the device's " + std::to_string(d.max_workgroup_count[1]) +
                    " workgroups along y");
    to_u32(int64_t(sets) * (int64_t(Na) + Nb), "nearest-distance array size");
    to_u32(numel(a.in[0].shape), "A size");
    // Where the device has subgroup shuffles (param subgroup = 0 forces the tiles),
    // target rows pass between lanes by shuffles: one query per thread, 64 per
    // workgroup (whole subgroups) so that a small set still spreads over cores.
    // Otherwise the shared-memory tile holds one target row per thread (one or two
    // vec3, 16 bytes each), two queries per thread. Either way one dispatch scans
    // at most kTargetChunk targets per query (the loop budget of ops/common.h), the
    // later ones keeping the smaller distance.
    const bool shuffle = shuffles_allowed(a);
    uint32_t local = shuffle ? subgroup_group_size(d) : elementwise_local_size(d);
    while (!shuffle && local > 1 && local * (D / 3) * 16 > d.max_shared_memory) local /= 2;
    // Queries per thread of the shuffle shader (param queries, 0: the device's choice,
    // measured here on vtloc-lite's 256 x 1024 rows of 6: ops/common.h).
    uint32_t Q = uint32_t(a.params.get("queries", 0));
    if (!shuffle) Q = 1;
    else if (Q == 0) Q = answers_per_shuffle(d);
    const uint32_t per_group = shuffle ? Q * local : 2 * local;
    const uint64_t ga = (Na + per_group - 1) / per_group, gb = (Nb + per_group - 1) / per_group;
    if (ga + gb > d.max_workgroup_count[0])
        throw Error("point sets of " + std::to_string(Na) + " and " + std::to_string(Nb) +
                    " rows need more workgroups than the device allows");
    const rt::Pipeline& nn = shuffle ? pipeline(a.ctx, "chamfer_nn_subgroup", 3, 20, {local, D == 6 ? 1u : 0u, Q})
                                     : pipeline(a.ctx, "chamfer_nn", 3, 20, {local, D == 6 ? 1u : 0u});
    for (uint32_t t0 = 0; t0 < std::max(Na, Nb); t0 += kTargetChunk) {
        struct { uint32_t Na, Nb, groups_a, t_begin, t_chunk; } push{Na, Nb, uint32_t(ga), t0, kTargetChunk};
        a.seq.dispatch(nn,
                       {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read},
                        {a.out[1].view, t0 == 0 ? rt::Access::Write : rt::Access::ReadWrite}},
                       &push, sizeof(push), uint32_t(ga + gb), sets);
    }
    struct { uint32_t Na, Nb; } push{Na, Nb};
    uint32_t sum_local = elementwise_local_size(d);
    while (sum_local > 1 && sum_local * 8 > d.max_shared_memory) sum_local /= 2;
    a.seq.dispatch(pipeline(a.ctx, "chamfer_sum", 2, 8, {sum_local}),
                   {{a.out[1].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write}}, &push, 8, sets);
}

}  // namespace

const OpDef op_chamfer{"chamfer", infer, cpu, gpu, 0, {"subgroup", "queries"}};

}  // namespace vtloc::ops
