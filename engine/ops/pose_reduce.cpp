// The multi-touch filter's reductions of its belief (SPEC 6):
// spin_marginal: prob [S * NS] -> [S], the belief at each surface sample (param n_spin);
// expected_distance: points [S, 3], weights [S], answers [A, 3] -> cost [A],
// cost_j = sum_s w_s ||p_s - a_j||, whose argmin is the Bayes estimate of the contact
// for the distance error (the tracker asks it of a strided subset of its samples).
// -> shaders/spin_marginal.glsl, shaders/expected_distance_subgroup.glsl (rows passed by
// subgroup shuffles) or shaders/expected_distance.comp (shared-memory tiles: devices
// without shuffles, or param subgroup = 0). The .glsl bodies read their inputs as texel
// buffers (.comp) or, past the device's texel limit or with param texel = 0, storage
// buffers (_ssbo.comp).
#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

int64_t n_spin(const Params& p) {
    double v = p.get("n_spin", 0);
    if (!(v >= 1) || v != std::floor(v) || v > 65536) throw Error("n_spin must be an integer in [1, 65536]");
    return int64_t(v);
}

std::vector<TensorDesc> marginal_infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 1, 1);
    expect_f32(in);
    const int64_t NS = n_spin(p);
    if (in[0].shape.size() != 1 || in[0].shape[0] == 0 || in[0].shape[0] % NS)
        throw Error("spin_marginal needs a flat [S * " + std::to_string(NS) + "] belief, got " + shape_str(in[0].shape));
    to_u32(in[0].shape[0], "belief size");
    return {TensorDesc{{in[0].shape[0] / NS}}};
}

void marginal_cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const int64_t NS = n_spin(p), S = out[0]->shape[0];
    for (int64_t s = 0; s < S; ++s) {
        float acc = 0;
        for (int64_t j = 0; j < NS; ++j) acc += in[0]->data[size_t(s * NS + j)];
        out[0]->data[size_t(s)] = acc;
    }
}

void marginal_gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    struct { uint32_t S, NS; } push{uint32_t(a.out[0].shape[0]), uint32_t(n_spin(a.params))};
    const uint32_t local = elementwise_local_size(d), groups = grid_groups(push.S, local, d);
    const uint64_t strides = (uint64_t(push.S) + uint64_t(groups) * local - 1) / (uint64_t(groups) * local);
    check_loop_budget(d, strides * (push.NS + 1), "spin_marginal");
    // prob as a texel buffer where the device allows (a gather on a CPU driver).
    const bool texel = texels_allowed(a, {uint64_t(a.in[0].shape[0])});
    a.seq.dispatch(a.ctx.pipelines().get(rt::PipelineDesc{texel ? "spin_marginal" : "spin_marginal_ssbo", 2,
                                                          uint32_t(sizeof(push)), {local}, texel ? 1u : 0u}),
                   {{a.in[0].view, rt::Access::Read, texel ? VK_FORMAT_R32_SFLOAT : VK_FORMAT_UNDEFINED},
                    {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), groups);
}

std::vector<TensorDesc> expect_infer(const std::vector<TensorDesc>& in, const Params&) {
    expect_input_count(in, 3, 3);
    expect_f32(in);
    const Shape &pt = in[0].shape, &w = in[1].shape, &an = in[2].shape;
    if (pt.size() != 2 || pt[1] != 3 || pt[0] == 0) throw Error("points must be [S > 0, 3], got " + shape_str(pt));
    if (w != Shape{pt[0]}) throw Error("weights must be [S] = " + shape_str({pt[0]}) + ", got " + shape_str(w));
    if (an.size() != 2 || an[1] != 3 || an[0] == 0) throw Error("answers must be [A > 0, 3], got " + shape_str(an));
    to_u32(3 * pt[0], "point array size");
    to_u32(3 * an[0], "answer array size");
    return {TensorDesc{{an[0]}}};
}

void expect_cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    const std::vector<float>&pt = in[0]->data, &w = in[1]->data, &an = in[2]->data;
    const size_t S = w.size(), A = an.size() / 3;
    for (size_t j = 0; j < A; ++j) {
        double acc = 0;
        for (size_t s = 0; s < S; ++s) {
            double e[3] = {double(pt[3 * s]) - an[3 * j], double(pt[3 * s + 1]) - an[3 * j + 1],
                           double(pt[3 * s + 2]) - an[3 * j + 2]};
            acc += double(w[s]) * std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        }
        out[0]->data[j] = float(acc);
    }
}

// The shuffle shader: chamfer's workgroup size and answers per thread (ops/common.h).
void expect_gpu_subgroup(const GpuOpArgs& a, uint32_t S, uint32_t A) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t Q = answers_per_shuffle(d), sg = std::max(1u, d.subgroup_size), local = subgroup_group_size(d);
    const uint64_t groups = (uint64_t(A) + uint64_t(Q) * local - 1) / (uint64_t(Q) * local);
    if (groups > d.max_workgroup_count[0])
        throw Error("expected_distance: " + std::to_string(A) + " answers need more workgroups than the device's " +
                    std::to_string(d.max_workgroup_count[0]));
    check_loop_budget(d, uint64_t(S) + 2 * ((uint64_t(S) + sg - 1) / sg) + 8, "expected_distance over " + std::to_string(S) + " points");
    struct { uint32_t S, A; } push{S, A};
    // The rows as texel buffers where the device allows (gathers on a CPU driver).
    const bool texel = texels_allowed(a, {3ull * S});
    const VkFormat f = texel ? VK_FORMAT_R32_SFLOAT : VK_FORMAT_UNDEFINED;
    a.seq.dispatch(a.ctx.pipelines().get(rt::PipelineDesc{texel ? "expected_distance_subgroup" : "expected_distance_subgroup_ssbo",
                                                          4, uint32_t(sizeof(push)), {local, Q}, texel ? 3u : 0u}),
                   {{a.in[0].view, rt::Access::Read, f}, {a.in[1].view, rt::Access::Read, f}, {a.in[2].view, rt::Access::Read},
                    {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), uint32_t(groups));
}

void expect_gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    struct { uint32_t S, A; } push{uint32_t(a.in[0].shape[0]), uint32_t(a.in[2].shape[0])};
    if (shuffles_allowed(a)) return expect_gpu_subgroup(a, push.S, push.A);
    uint32_t local = elementwise_local_size(d);
    while (local > 1 && local * 16 + 4 > d.max_shared_memory) local /= 2;  // the tile and its count
    const uint64_t groups = (uint64_t(push.A) + local - 1) / local, tiles = (uint64_t(push.S) + local - 1) / local;
    if (groups > d.max_workgroup_count[0])
        throw Error("expected_distance: " + std::to_string(push.A) + " answers need more workgroups than the device's " +
                    std::to_string(d.max_workgroup_count[0]));
    check_loop_budget(d, 2 * uint64_t(push.S) + 3 * tiles + 8, "expected_distance over " + std::to_string(push.S) + " points");
    a.seq.dispatch(pipeline(a.ctx, "expected_distance", 4, sizeof(push), {local}),
                   {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read}, {a.in[2].view, rt::Access::Read},
                    {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), uint32_t(groups));
}

}  // namespace

const OpDef op_spin_marginal{"spin_marginal", marginal_infer, marginal_cpu, marginal_gpu, 0, {"n_spin", "texel"}};
const OpDef op_expected_distance{"expected_distance", expect_infer, expect_cpu, expect_gpu, 0, {"subgroup", "texel"}};

}  // namespace vtloc::ops
