// heatmap: rank-weighted heat-map over the cloud (SPEC 3, weights_tools/post.py
// heatmap): w = rank of the nearest top-K centre (lowest rank on a tie),
// s_p = exp(-||p - c*_w||) / w, min-max normalised (all zeros when flat).
// -> shaders/heatmap_subgroup.comp (both steps in one dispatch, one subgroup per
// row) on a device with subgroup shuffles, else shaders/heatmap_score.comp (per
// point) + shaders/heatmap_norm.comp (the min/max reduction and the
// normalisation, one workgroup). Param subgroup = 0 forces the second.
// Inputs: cloud [P, D >= 3] (xyz first), candidates [M, 3], topk index I32 [K]
// (rank order), optionally the symmetry prior as T affine maps [T, 12] (3x4
// row-major, symmetry_transforms in engine/model/post.h makes them). Output [P].
// A batch: index [B, K] (B > 1, one top-K per touch) gives [B, P], one heat-map
// per row (workgroup y of the score pass, one normalising workgroup per row).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    expect_input_count(in, 3, 4);
    const Shape &cloud = in[0].shape, &cand = in[1].shape, &idx = in[2].shape;
    if (in[0].type != ElemType::F32 || in[1].type != ElemType::F32 || (in.size() == 4 && in[3].type != ElemType::F32))
        throw Error("cloud, candidates and symmetry maps must be F32");
    if (in[2].type != ElemType::I32) throw Error("top-K index must be I32");
    if (cloud.size() != 2 || cloud[1] < 3) throw Error("cloud must be [P, D >= 3], got " + shape_str(cloud));
    if (cloud[0] == 0) throw Error("the cloud is empty");
    if (cand.size() != 2 || cand[1] != 3 || cand[0] == 0) throw Error("candidates must be [M > 0, 3], got " + shape_str(cand));
    if (idx.empty() || idx.size() > 2 || numel(idx) == 0)
        throw Error("top-K index must be [K > 0] or a batch [B, K > 0], got " + shape_str(idx));
    if (in.size() == 4 && (in[3].shape.size() != 2 || in[3].shape[1] != 12 || in[3].shape[0] == 0))
        throw Error("symmetry maps must be [T > 0, 12], got " + shape_str(in[3].shape));
    to_u32(numel(cloud), "cloud size");
    to_u32(numel(cand), "candidate array size");
    const int64_t B = idx.size() == 2 ? idx[0] : 1;
    to_u32(B * cloud[0], "heat-map batch size");
    return {TensorDesc{B > 1 ? Shape{B, cloud[0]} : Shape{cloud[0]}}};
}

// One heat-map from the top-K indices idx[0, K) into out[0, P).
void heat_row(const HostTensor& cloud, const HostTensor& cand, const int32_t* idx, int64_t K, const HostTensor* sym,
              float* out) {
    const int64_t P = cloud.shape[0], D = cloud.shape[1], M = cand.shape[0];
    // Centres with their ranks, copy order (rank, copy) as the reference builds them.
    std::vector<std::array<double, 3>> centres;
    std::vector<int> ranks;
    const int64_t T = sym ? sym->shape[0] : 0;
    for (int64_t j = 0; j < K; ++j) {
        int32_t ci = idx[j];
        if (ci < 0 || ci >= M) throw Error("heat-map: top-K index " + std::to_string(ci) + " is outside 0.." + std::to_string(M - 1));
        const float* c = &cand.data[size_t(3 * ci)];
        for (int64_t t = 0; t < std::max<int64_t>(T, 1); ++t) {
            std::array<double, 3> ct{c[0], c[1], c[2]};
            if (T > 0) {
                const float* a = &sym->data[size_t(12 * t)];
                for (int r = 0; r < 3; ++r)
                    ct[size_t(r)] = double(a[4 * r]) * c[0] + double(a[4 * r + 1]) * c[1] + double(a[4 * r + 2]) * c[2] + a[4 * r + 3];
            }
            centres.push_back(ct);
            ranks.push_back(int(j + 1));
        }
    }
    std::vector<double> s(static_cast<size_t>(P));
    for (int64_t i = 0; i < P; ++i) {
        const float* pt = &cloud.data[size_t(i * D)];
        double best = std::numeric_limits<double>::infinity();
        int w = 1;
        for (size_t c = 0; c < centres.size(); ++c) {
            double dx = pt[0] - centres[c][0], dy = pt[1] - centres[c][1], dz = pt[2] - centres[c][2];
            double d = std::sqrt((dx * dx + dy * dy) + dz * dz);
            if (d < best) best = d, w = ranks[c];  // strict: ties keep the lower rank
        }
        s[size_t(i)] = std::exp(-best) / w;
    }
    auto [lo, hi] = std::minmax_element(s.begin(), s.end());
    for (int64_t i = 0; i < P; ++i) out[i] = *hi == *lo ? 0.0f : float((s[size_t(i)] - *lo) / (*hi - *lo));
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    for (const HostTensor* t : {in[0], in[1]})
        for (float v : t->data)
            if (!std::isfinite(v)) throw Error(std::string("heat-map: the ") + (t == in[0] ? "cloud" : "candidates") + " hold NaN or inf");
    const HostTensor& idx = *in[2];
    const int64_t B = idx.shape.size() == 2 ? idx.shape[0] : 1, K = idx.shape.back(), P = in[0]->shape[0];
    const std::vector<int32_t> all = idx.ints();
    for (int64_t b = 0; b < B; ++b)
        heat_row(*in[0], *in[1], &all[size_t(b * K)], K, in.size() == 4 ? in[3] : nullptr, &out[0]->data[size_t(b * P)]);
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t local = elementwise_local_size(d);
    const bool sym = a.in.size() == 4;
    const Shape& idx = a.in[2].shape;
    const uint32_t B = idx.size() == 2 ? to_u32(idx[0], "heat-map batch") : 1u;
    if (B > d.max_workgroup_count[1] || B > d.max_workgroup_count[0])
        throw Error("a heat-map batch of " + std::to_string(B) + " exceeds the device's workgroup count limits");
    struct { uint32_t P, D, M, K, T; } push{uint32_t(a.in[0].shape[0]), uint32_t(a.in[0].shape[1]),
                                          uint32_t(a.in[1].shape[0]), to_u32(idx.back(), "K"),
                                          sym ? to_u32(a.in[3].shape[0], "symmetry maps") : 0u};
    // One dispatch, one subgroup per row, where the device has shuffles, the cloud
    // fits its texel limit and one lane's scan stays within the loop budget
    // (param subgroup = 0 forces the two passes).
    const uint32_t sg = std::max(1u, d.subgroup_size);
    if (shuffles_allowed(a) && heatmap_subgroup_iterations(push.P, push.K, push.T, sg) <= kLoopIterationBudget &&
        uint64_t(numel(a.in[0].shape)) <= d.max_texel_elements) {
        // Up to 16 centres without symmetry are loaded once into every lane (the shader's KR).
        const uint32_t kr = !sym && push.K <= 16 ? push.K : 0u;
        a.seq.dispatch(a.ctx.pipelines().get(rt::PipelineDesc{"heatmap_subgroup", 5, 20, {sg, kr}, 0x1u}),
                       {{a.in[0].view, rt::Access::Read, VK_FORMAT_R32_SFLOAT}, {a.in[1].view, rt::Access::Read},
                        {a.in[2].view, rt::Access::Read}, {(sym ? a.in[3] : a.in[1]).view, rt::Access::Read},
                        {a.out[0].view, rt::Access::ReadWrite}},
                       &push, sizeof(push), 1, B);
        return;
    }
    a.seq.dispatch(pipeline(a.ctx, "heatmap_score", 5, 20, {local}),
                   {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read},
                    {a.in[2].view, rt::Access::Read}, {(sym ? a.in[3] : a.in[1]).view, rt::Access::Read},
                    {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), grid_groups(push.P, local, d), B);
    uint32_t norm_local = local;
    while (norm_local > 1 && norm_local * 8 > d.max_shared_memory) norm_local /= 2;
    a.seq.dispatch(pipeline(a.ctx, "heatmap_norm", 1, 4, {norm_local}), {{a.out[0].view, rt::Access::ReadWrite}},
                   &push.P, 4, B);
}

}  // namespace

uint64_t heatmap_subgroup_iterations(int64_t P, int64_t K, int64_t T, uint32_t subgroup) {
    const uint64_t sg = std::max(1u, subgroup);
    return (uint64_t(P) + sg - 1) / sg * (2 + uint64_t(K) * uint64_t(1 + std::max<int64_t>(T, 1))) + 64;
}

const OpDef op_heatmap{"heatmap", infer, cpu, gpu, 0, {"subgroup"}};

}  // namespace vtloc::ops
