// The gel's shape from a frame (SPEC 9, docs/gel_shape.md), its two GPU steps:
// gel_gradient: frame [H, W, 3], empty [H, W, 3] (grey levels), tables [T, n^3, 2], linear
//   [H, W, 6] -> the indentation's gradient [H, W, 2] (params n, tiles_y, tiles_x, gentle; T =
//   tiles_y * tiles_x): the tables' answer, or the linearised inverse where it is gentle;
// masked_poisson: gradient [H, W, 2], mask [H, W] (> 0.5: contact)[, start [H, W]] -> the height [H, W] and a
//   workspace (i32, unspecified: the pixels each half-sweep updates) (params iterations, omega):
//   red-black SOR of lap(z) = div(g) inside the mask, z = 0 outside it, the image's border free,
//   from the start where given (a coarser solve's answer, op poisson_prolong), else from zeros.
// CPU references: engine/ops/gel_ops.h, operation for operation. -> shaders/gel_gradient.comp,
// shaders/masked_poisson.comp: two set-up dispatches (the lists' lengths cleared; then z set, to
// the start or 0, and per colour a list of the pixels to update with their divergence), then one dispatch per half-sweep over that colour's list, in
// all workgroups (the sequence's barrier between dependent dispatches orders the colours; one
// workgroup with a barrier between colours, as before, ran serially on a CPU device, which gives
// a workgroup one thread: 76 of lavapipe's 79 ms for a 120 x 160 frame; docs/gel_shape.md).
#include <algorithm>
#include <cmath>
#include <thread>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/gel_ops.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

int int_param(const Params& p, const char* k, double lo, double hi) {
    const double v = p.get(k, -1);
    if (!(v >= lo && v <= hi) || v != std::floor(v))
        throw Error(std::string(k) + " must be an integer in [" + std::to_string(int64_t(lo)) + ", " + std::to_string(int64_t(hi)) + "]");
    return int(v);
}

std::vector<TensorDesc> gradient_infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 4, 4);
    expect_f32(in);
    const int n = int_param(p, "n", 2, 256), ty = int_param(p, "tiles_y", 1, 64), tx = int_param(p, "tiles_x", 1, 64);
    const double gentle = p.get("gentle", -1);
    if (!(gentle >= 0 && gentle < 1e6)) throw Error("gel_gradient: gentle must be >= 0 (0: the tables everywhere)");
    const Shape& f = in[0].shape;
    if (f.size() != 3 || f[2] != 3 || f[0] < 1 || f[1] < 1) throw Error("gel_gradient: the frame must be [H, W, 3], got " + shape_str(f));
    if (in[1].shape != f) throw Error("gel_gradient: the empty frame must be " + shape_str(f) + ", got " + shape_str(in[1].shape));
    const Shape want{int64_t(ty) * tx, int64_t(n) * n * n, 2};
    if (in[2].shape != want) throw Error("gel_gradient: the tables must be " + shape_str(want) + ", got " + shape_str(in[2].shape));
    if (in[3].shape != Shape{f[0], f[1], 6})
        throw Error("gel_gradient: the linear inverse must be " + shape_str({f[0], f[1], 6}) + ", got " + shape_str(in[3].shape));
    to_u32(f[0] * f[1] * 6, "linear inverse size");
    to_u32(in[2].shape[0] * in[2].shape[1] * 2, "table size");
    to_u32(f[0] * f[1] * 3, "frame size");
    return {TensorDesc{{f[0], f[1], 2}}};
}

void gradient_cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const int n = int(p.get("n", 0)), ty = int(p.get("tiles_y", 0)), tx = int(p.get("tiles_x", 0));
    const int H = int(in[0]->shape[0]), W = int(in[0]->shape[1]);
    for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c) {
            float* g = &out[0]->data[(size_t(r) * size_t(W) + size_t(c)) * 2];
            gel::indentation_gradient(in[2]->data.data(), n, ty, tx, H, W, in[0]->data.data(), in[1]->data.data(),
                                      in[3]->data.data(), float(p.get("gentle", 0)), r, c, g[0], g[1]);
        }
}

void gradient_gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    struct { int32_t H, W, n, ty, tx; float gentle; } push{int32_t(a.in[0].shape[0]), int32_t(a.in[0].shape[1]), int32_t(a.params.get("n", 0)),
                                                           int32_t(a.params.get("tiles_y", 0)), int32_t(a.params.get("tiles_x", 0)),
                                                           float(a.params.get("gentle", 0))};
    const uint64_t HW = uint64_t(push.H) * uint64_t(push.W);
    const uint32_t local = elementwise_local_size(d), groups = grid_groups(HW, local, d);
    check_loop_budget(d, (HW + uint64_t(groups) * local - 1) / (uint64_t(groups) * local) * 8, "gel_gradient");
    a.seq.dispatch(pipeline(a.ctx, "gel_gradient", 5, sizeof(push), {local}),
                   {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read}, {a.in[2].view, rt::Access::Read},
                    {a.in[3].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), groups);
}

// The workspace's room for one colour's list (its pixels, at most ceil(H W / 2)), in entries of
// two words; the lists start after the two lengths.
int64_t poisson_list_cap(int64_t H, int64_t W) {
    const int64_t cap = (H * W + 1) / 2;
    to_u32(2 + 4 * cap, "masked_poisson workspace size");
    return cap;
}

std::vector<TensorDesc> poisson_infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 2, 3);
    expect_f32(in);
    int_param(p, "iterations", 0, 10000);  // two dispatches a sweep on the GPU
    const double w = p.get("omega", -1);
    if (!(w > 0 && w < 2)) throw Error("masked_poisson: omega must be in (0, 2)");
    const Shape& g = in[0].shape;
    if (g.size() != 3 || g[2] != 2 || g[0] < 1 || g[1] < 1) throw Error("masked_poisson: the gradient must be [H, W, 2], got " + shape_str(g));
    if (in[1].shape != Shape{g[0], g[1]}) throw Error("masked_poisson: the mask must be " + shape_str({g[0], g[1]}) + ", got " + shape_str(in[1].shape));
    if (in.size() == 3 && in[2].shape != Shape{g[0], g[1]})
        throw Error("masked_poisson: the start must be " + shape_str({g[0], g[1]}) + ", got " + shape_str(in[2].shape));
    to_u32(g[0] * g[1] * 2, "gradient size");
    return {TensorDesc{{g[0], g[1]}}, TensorDesc{{2 + 4 * poisson_list_cap(g[0], g[1])}, ElemType::I32}};
}

void poisson_cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    gel::masked_poisson(in[0]->data.data(), in[1]->data.data(), int(in[0]->shape[0]), int(in[0]->shape[1]),
                        int(p.get("iterations", 0)), float(p.get("omega", 1)), out[0]->data.data(),
                        in.size() == 3 ? in[2]->data.data() : nullptr);
    std::fill(out[1]->data.begin(), out[1]->data.end(), 0.0f);
}

void poisson_gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const int32_t H = int32_t(a.in[0].shape[0]), W = int32_t(a.in[0].shape[1]), iterations = int32_t(a.params.get("iterations", 0));
    const uint64_t HW = uint64_t(H) * uint64_t(W), cap = uint64_t(poisson_list_cap(H, W));
    // A CPU device starts each workgroup at a cost (lavapipe: a 120 x 160 half-sweep's 38 groups
    // of 256 took ~80 us a dispatch, 2 groups ~20): there, one group per host thread.
    const uint32_t local = elementwise_local_size(d);
    const uint32_t most = d.type == VK_PHYSICAL_DEVICE_TYPE_CPU ? std::max(1u, std::thread::hardware_concurrency()) : 0xffffffffu;
    const uint32_t groups = std::min(most, grid_groups(HW, local, d)), sweep_groups = std::min(most, grid_groups(cap, local, d));
    const uint64_t lanes = uint64_t(groups) * local, sweep_lanes = uint64_t(sweep_groups) * local;
    check_loop_budget(d, std::max((HW + lanes - 1) / lanes, (cap + sweep_lanes - 1) / sweep_lanes), "masked_poisson");
    struct { int32_t H, W, colour; uint32_t cap; float omega; } push{H, W, 0, uint32_t(cap), float(a.params.get("omega", 1))};
    const rt::BufferView grad = a.in[0].view, mask = a.in[1].view, z = a.out[0].view, ws = a.out[1].view;
    // Without a start, binding 4 is the mask (same size, never read: kHasStart is off).
    const bool has_start = a.in.size() == 3;
    const rt::BufferView start = has_start ? a.in[2].view : mask;
    auto stage = [&](uint32_t s) -> const rt::Pipeline& {
        return pipeline(a.ctx, "masked_poisson", 5, sizeof(push), {local, s, uint32_t(has_start)});
    };
    const rt::Binding read_start{start, rt::Access::Read};
    a.seq.dispatch(stage(0), {{grad, rt::Access::Read}, {mask, rt::Access::Read}, {z, rt::Access::Write}, {ws, rt::Access::Write}, read_start},
                   &push, sizeof(push), 1);
    a.seq.dispatch(stage(1), {{grad, rt::Access::Read}, {mask, rt::Access::Read}, {z, rt::Access::Write}, {ws, rt::Access::ReadWrite}, read_start},
                   &push, sizeof(push), groups);
    const rt::Pipeline& sweep = stage(2);
    for (int32_t h = 0; h < 2 * iterations; ++h) {
        push.colour = h & 1;
        a.seq.dispatch(sweep, {{grad, rt::Access::Read}, {mask, rt::Access::Read}, {z, rt::Access::ReadWrite}, {ws, rt::Access::Read}, read_start},
                       &push, sizeof(push), sweep_groups);
    }
}

}  // namespace

const OpDef op_gel_gradient{"gel_gradient", gradient_infer, gradient_cpu, gradient_gpu, 0, {"n", "tiles_y", "tiles_x", "gentle"}};
const OpDef op_masked_poisson{"masked_poisson", poisson_infer, poisson_cpu, poisson_gpu, 1u << 1, {"iterations", "omega"}};

}  // namespace vtloc::ops
