// fps: farthest point sampling (SPEC 2) -> shaders/fps.comp, one workgroup
// (fps_subgroup.comp where the device has subgroup arithmetic; param subgroup = 0
// forces fps.comp).
// Input: points [N, D >= 3] (xyz = columns 0..2, the rest ignored).
// Param npoint (1..N). Outputs: index I32 [npoint], centres F32 [npoint, 3]
// (the picked xyz, what the next stage groups around), and a workspace F32 [N]
// (running minimum distances when they do not fit in registers; contents unspecified).
// Param threads (tests, bench): the workgroup size, a power of two within the device's
// limits, instead of the device's choice (points a thread keep in registers up to 32).
#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"
#include "engine/ops/point_common.h"

namespace vtloc::ops {
namespace {

constexpr uint32_t kMaxPer = 16;     // points a thread keeps in registers
constexpr uint32_t kMaxPerCpu = 32;  // the same on CPU devices (see gpu())

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 1, 1);
    expect_f32(in);
    if (p.has("threads")) pow2_param(p, "threads", 1, 1024);
    const Shape& s = in[0].shape;
    if (s.size() != 2 || s[1] < 3) throw Error("points must be [N, D >= 3], got " + shape_str(s));
    if (s[0] == 0) throw Error("the point cloud is empty");
    const int64_t S = int_param(p, "npoint", 1, std::numeric_limits<int32_t>::max());
    if (S > s[0])
        throw Error("cannot sample " + std::to_string(S) + " points from a cloud of " + std::to_string(s[0]));
    to_u32(numel(s), "point array size");
    return {TensorDesc{{S}, ElemType::I32}, TensorDesc{{S, 3}}, TensorDesc{{s[0]}}};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    const HostTensor& x = *in[0];
    const int64_t N = x.shape[0], D = x.shape[1], S = out[0]->size();
    require_finite_xyz(x, "fps");
    std::vector<float> mind(size_t(N), std::numeric_limits<float>::infinity());
    int64_t far = 0;
    for (int64_t s = 0; s < S; ++s) {
        out[0]->set_int(size_t(s), int32_t(far));
        const float* c = &x.data[size_t(far * D)];
        for (int k = 0; k < 3; ++k) out[1]->data[size_t(3 * s + k)] = c[k];
        int64_t best_i = 0;
        float best = -1.0f;
        for (int64_t i = 0; i < N; ++i) {
            mind[size_t(i)] = std::min(mind[size_t(i)], sqdist3(&x.data[size_t(i * D)], c));
            if (mind[size_t(i)] > best) best = mind[size_t(i)], best_i = i;  // first maximum = lowest index
        }
        far = best_i;
    }
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t N = to_u32(a.in[0].shape[0], "points"), S = to_u32(a.out[0].shape[0], "npoint");
    // A power of two (the tree reduction halves it) within the limits and the
    // shared memory (2 x 8 bytes per thread). About 8 points per thread where the
    // tree's log2(L) barriers a step are the cost; a GPU with subgroup arithmetic
    // (one barrier a step) takes 2 points a thread: on an H200 (2026-12-04, bench
    // "FPS by workgroup size") the paper's SA1 at 512 threads took 0.74x the time of
    // 128 threads, SA2's 512 -> 128 at 256 threads 0.69x that of 64.
    const uint32_t cap = std::min({1024u, d.max_invocations, d.max_workgroup_size[0], d.max_shared_memory / 16});
    const uint32_t sg = std::max(1u, d.subgroup_size);
    struct Plan {
        uint32_t L, per;
        bool regs;
        uint64_t tree_iters, subgroup_iters;
    };
    // Loop iterations per step: a pass over the thread's points unless they sit in
    // registers (a constant trip count the compiler unrolls: 4,097 steps of 5 points
    // each run correctly on lavapipe; past kMaxPer counted as a loop, the unrolling
    // being the compiler's choice), then the tree's log2(L) rounds or, with
    // subgroup arithmetic (one barrier per step, fps.glsl), ceil(L / SG / SG) over
    // the subgroups' entries; on a CPU driver that path is taken only within the budget.
    auto plan = [&](uint32_t L, uint32_t max_per) {
        Plan p{L, (N + L - 1) / L, false, 0, 0};
        p.regs = p.per <= max_per && !a.params.get("no_registers", 0);
        uint32_t log_l = 0;
        while ((1u << log_l) < L) ++log_l;
        const uint64_t pass = p.regs && p.per <= kMaxPer ? 1 : p.per;
        p.tree_iters = uint64_t(S) * (pass + log_l + 1);
        p.subgroup_iters = uint64_t(S) * (pass + (L / sg + sg - 1) / sg + 1);
        return p;
    };
    const bool arithmetic = a.params.get("subgroup", 1) != 0 && (d.subgroup_ops & VK_SUBGROUP_FEATURE_ARITHMETIC_BIT) &&
                            (d.subgroup_ops & VK_SUBGROUP_FEATURE_BASIC_BIT);
    const uint32_t per_thread = arithmetic && d.type != VK_PHYSICAL_DEVICE_TYPE_CPU ? 2 : 8;
    uint32_t L = 1;
    while (L * 2 <= cap && (L < d.subgroup_size || L < 32 || uint64_t(L) * per_thread < N)) L *= 2;
    Plan pl = plan(L, kMaxPer);
    if (a.params.has("threads")) {
        L = uint32_t(a.params.get("threads", 1));
        if (L > cap)
            throw Error("threads = " + std::to_string(L) + " is over this device's " + std::to_string(cap) +
                        " (workgroup size and shared-memory limits)");
        pl = plan(L, kMaxPerCpu);
    }
    if (d.type == VK_PHYSICAL_DEVICE_TYPE_CPU && arithmetic && sg <= cap && !a.params.has("threads")) {
        // A CPU driver runs a workgroup's subgroups one after another, switching at
        // every barrier, while a lane's points cost only SIMD arithmetic: the fewest
        // subgroups that hold the cloud at 32 points a lane (one subgroup, no shared
        // memory or barrier, up to 32 x SG points). Measured on lavapipe: FPS of the
        // paper's SA1 (512 of 1024 points) 8-9 -> 1.9 ms; at 16 or 64 a lane 2.5-4.4 ms.
        uint32_t Lc = sg;
        while (Lc * 2 <= cap && uint64_t(Lc) * kMaxPerCpu < N) Lc *= 2;
        const Plan c = plan(Lc, kMaxPerCpu);
        if (c.regs && c.subgroup_iters <= kLoopIterationBudget) pl = c;
    }
    const bool subgroup = arithmetic && pl.L % sg == 0 &&
                          (d.type != VK_PHYSICAL_DEVICE_TYPE_CPU || pl.subgroup_iters <= kLoopIterationBudget);
    check_loop_budget(d, subgroup ? pl.subgroup_iters : pl.tree_iters,
                      "FPS of " + std::to_string(S) + " from " + std::to_string(N) + " points");
    struct { uint32_t N, D, S; } push{N, to_u32(a.in[0].shape[1], "point width"), S};
    a.seq.dispatch(pipeline(a.ctx, subgroup ? "fps_subgroup" : "fps", 4, sizeof(push), {pl.L, pl.regs ? pl.per : 1u, pl.regs ? 1u : 0u}),
                   {{a.in[0].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write},
                    {a.out[1].view, rt::Access::Write}, {a.out[2].view, rt::Access::ReadWrite}},
                   &push, sizeof(push), 1);
}

}  // namespace

const OpDef op_fps{"fps", infer, cpu, gpu, 1u << 2, {"npoint", "no_registers", "subgroup", "threads"}};  // output 2: the workspace

}  // namespace vtloc::ops
