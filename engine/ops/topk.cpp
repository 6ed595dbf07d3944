// topk: the K candidates nearest c^p (SPEC 3): S_i = ||c^p - c_i||^2 ascending,
// ties to the lower index. -> shaders/topk_subgroup.comp (K <= 16 on a device
// with subgroup shuffles: one subgroup per contact, keys in registers), else
// shaders/topk.comp, a few passes, each sorting chunks of S keys in shared
// memory and keeping K per chunk. Param subgroup = 0 forces the second.
// Inputs: contact [3] (or [1, 3]), candidates [M, 3]. Param k (1..256, <= M).
// Outputs: index I32 [K], score F32 [K], and a workspace (I32, contents
// unspecified) holding the intermediate key lists of the passes.
// A batch of contacts [B, 3] (B > 1) against the same candidates gives [B, K]
// outputs in one set of dispatches (workgroup y = the contact).
#include <algorithm>
#include <cmath>
#include <numeric>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

constexpr int64_t kRegionAlign = 256;  // the largest minStorageBufferOffsetAlignment Vulkan allows
// The register path: K keys per lane, one subgroup scanning every candidate while
// that scan stays within kLoopIterationBudget; beyond, the multi-pass sort.
constexpr int64_t kSubgroupMaxK = 16;

int64_t pow2_at_least(int64_t v) {
    int64_t p = 1;
    while (p < v) p *= 2;
    return p;
}
// The smallest chunk the host may pick; workspace regions are sized for it, so
// any larger chunk (fewer groups) fits too.
int64_t min_chunk(int64_t K) { return std::max<int64_t>(64, pow2_at_least(2 * K)); }
int64_t ceil_div(int64_t a, int64_t b) { return (a + b - 1) / b; }

// The workspace: region A (passes 0, 2, ...) then region B (passes 1, 3, ...),
// each holding one key list per contact of the batch, a_words / b_words apart.
struct Regions {
    int64_t a_words, b_words, b_offset_words, total_words;
};
Regions regions(int64_t M, int64_t K, int64_t batch) {
    const int64_t S = min_chunk(K);
    int64_t a_keys = ceil_div(M, S) * K, b_keys = ceil_div(a_keys, S) * K;
    int64_t b_off = ceil_div(batch * 2 * a_keys * 4, kRegionAlign) * kRegionAlign / 4;
    return {2 * a_keys, 2 * b_keys, b_off, b_off + batch * 2 * b_keys};
}
int64_t batch_of(const Shape& contact) { return contact.size() == 2 ? contact[0] : 1; }

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 2, 2);
    expect_f32(in);
    const Shape& cs = in[0].shape;
    if (cs.empty() || cs.size() > 2 || cs.back() != 3 || numel(cs) == 0)
        throw Error("contact must be [3] or a batch [B, 3], got " + shape_str(cs));
    const Shape& c = in[1].shape;
    if (c.size() != 2 || c[1] != 3) throw Error("candidates must be [M, 3], got " + shape_str(c));
    if (c[0] == 0) throw Error("the candidate set is empty");
    const double k = p.get("k", 0);
    if (!(k >= 1 && k <= double(kMaxTopK)) || k != std::floor(k))
        throw Error("K must be an integer in 1.." + std::to_string(kMaxTopK) + ", got " + std::to_string(k));
    if (int64_t(k) > c[0])
        throw Error("K = " + std::to_string(int64_t(k)) + " exceeds the " + std::to_string(c[0]) + " candidates");
    to_u32(c[0] * 3, "candidate array size");
    const int64_t K = int64_t(k), B = batch_of(cs);
    const Shape out = B > 1 ? Shape{B, K} : Shape{K};
    const int64_t ws = regions(c[0], K, B).total_words;
    to_u32(ws, "top-K workspace size");
    return {TensorDesc{out, ElemType::I32}, TensorDesc{out}, TensorDesc{{ws}, ElemType::I32}};
}

float score_of(const float* c, const float* p) {
    // The reference's order and roundings: (dx*dx + dy*dy) + dz*dz in float.
    float dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2];
    float xx = dx * dx, yy = dy * dy, zz = dz * dz;
    float xy = xx + yy;
    return xy + zz;
}

// The K best candidates for one contact c into (index, score)[0, K).
void select(const float* c, const HostTensor& cand, int64_t K, HostTensor& index, HostTensor& score, size_t at) {
    const int64_t M = cand.shape[0];
    std::vector<float> s(static_cast<size_t>(M));
    for (int64_t i = 0; i < M; ++i) {
        s[size_t(i)] = score_of(c, &cand.data[size_t(3 * i)]);
        if (!std::isfinite(s[size_t(i)]))
            throw Error("top-K: candidate " + std::to_string(i) + " holds NaN or inf (or its score overflows)");
    }
    std::vector<int32_t> order(static_cast<size_t>(M));
    std::iota(order.begin(), order.end(), 0);
    std::partial_sort(order.begin(), order.begin() + K, order.end(), [&](int32_t x, int32_t y) {
        return s[size_t(x)] < s[size_t(y)] || (s[size_t(x)] == s[size_t(y)] && x < y);
    });
    for (int64_t j = 0; j < K; ++j) {
        index.set_int(at + size_t(j), order[size_t(j)]);
        score.data[at + size_t(j)] = s[size_t(order[size_t(j)])];
    }
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    for (float v : in[0]->data)
        if (!std::isfinite(v)) throw Error("top-K: the contact holds NaN or inf");
    const int64_t B = batch_of(in[0]->shape), K = out[0]->size() / B;
    for (int64_t b = 0; b < B; ++b) select(&in[0]->data[size_t(3 * b)], *in[1], K, *out[0], *out[1], size_t(b * K));
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const int64_t M = a.in[1].shape[0], B = batch_of(a.in[0].shape), K = a.out[0].shape.back();
    if (B > int64_t(d.max_workgroup_count[1]))
        throw Error("a top-K batch of " + std::to_string(B) + " contacts exceeds the device's " +
                    std::to_string(d.max_workgroup_count[1]) + " workgroups along y");
    // Small K on a device with shuffles (param subgroup = 0 forces the sort): one
    // subgroup per contact keeps its K best in registers (topk_subgroup.comp).
    const uint32_t sg = d.subgroup_size;
    if (shuffles_allowed(a) && K <= kSubgroupMaxK &&
        uint64_t(M) * 3 <= d.max_texel_elements &&
        topk_subgroup_iterations(M, K, sg) <= kLoopIterationBudget) {
        struct { uint32_t n; } push{uint32_t(M)};
        a.seq.dispatch(a.ctx.pipelines().get(rt::PipelineDesc{"topk_subgroup", 4, 4, {sg, uint32_t(K)}, 0x2u}),
                       {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read, VK_FORMAT_R32_SFLOAT},
                        {a.out[0].view, rt::Access::Write}, {a.out[1].view, rt::Access::Write}},
                       &push, sizeof(push), 1, uint32_t(B));
        return;
    }
    // The largest chunk using at most half the shared memory, up to 2048 keys,
    // and no larger than the candidates need (a smaller sort).
    int64_t S = min_chunk(K);
    while (S < 2048 && S < M && S * 2 * 8 <= int64_t(d.max_shared_memory) / 2) S *= 2;
    if (S * 8 > int64_t(d.max_shared_memory))
        throw Error("top-K with K = " + std::to_string(K) + " needs more shared memory than the device has");
    const uint32_t L = std::min<uint32_t>(elementwise_local_size(d), uint32_t(S / 2));
    const Regions r = regions(M, K, B);
    const rt::BufferView& ws = a.out[2].view;
    const rt::BufferView region[2] = {{ws.buffer, ws.offset, uint64_t(std::max<int64_t>(1, B * r.a_words)) * 4},
                                      {ws.buffer, ws.offset + uint64_t(r.b_offset_words) * 4,
                                       uint64_t(std::max<int64_t>(1, r.total_words - r.b_offset_words)) * 4}};
    const int64_t stride[2] = {r.a_words, r.b_words};
    int64_t n = M;
    for (int pass = 0;; ++pass) {
        const int64_t groups = ceil_div(n, S);
        if (groups > int64_t(d.max_workgroup_count[0])) throw Error("too many candidates for one top-K pass on this device");
        const bool first = pass == 0, final = groups == 1;
        // Per-contact word strides of the source and destination key lists (the
        // first pass reads the shared candidates).
        struct { uint32_t n, K, src_stride, dst_stride; } push{
            uint32_t(n), uint32_t(K), first ? 0u : uint32_t(stride[(pass - 1) % 2]), final ? 0u : uint32_t(stride[pass % 2])};
        const rt::BufferView& src = first ? a.in[1].view : region[(pass - 1) % 2];
        const rt::BufferView& dst = final ? a.in[0].view : region[pass % 2];  // unused when final
        a.seq.dispatch(pipeline(a.ctx, "topk", 5, 16, {L, uint32_t(S), first, final}),
                       {{a.in[0].view, rt::Access::Read}, {src, rt::Access::Read},
                        {dst, final ? rt::Access::Read : rt::Access::Write},
                        {a.out[0].view, final ? rt::Access::Write : rt::Access::Read},
                        {a.out[1].view, final ? rt::Access::Write : rt::Access::Read}},
                       &push, sizeof(push), uint32_t(groups), uint32_t(B));
        if (final) break;
        n = groups * K;
    }
}

}  // namespace

uint64_t topk_subgroup_iterations(int64_t M, int64_t K, uint32_t subgroup) {
    const uint64_t sg = std::max(1u, subgroup);
    return (uint64_t(M) + sg - 1) / sg * uint64_t(K + 1) + uint64_t(K) * uint64_t(K + 8);
}

const OpDef op_topk{"topk", infer, cpu, gpu, 1u << 2, {"k", "subgroup"}};  // output 2: the workspace

}  // namespace vtloc::ops
