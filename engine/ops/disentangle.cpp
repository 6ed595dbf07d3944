// disentangle: GMA's einsum y[..., j, l] = act(sum_i x[..., i] W[i, j, l]), i.e. a
// GEMM whose weight is stored [K, N] (not Linear's [N, K]). -> shaders/disentangle.comp
// (X staged through shared memory), or disentangle_subgroup.comp (X by subgroup
// shuffles, W as texels) where the device has shuffles; param subgroup = 0 forces
// the first.
// Inputs: x [..., K], then W as one or more row chunks [K_c, ...] (same trailing
// dims, rows summing to K) so that no chunk exceeds maxStorageBufferRange;
// split_weight_rows (engine/model/gma.h) makes the chunks. One dispatch per
// chunk, each adding its partial sum. Params: act (Act, default none), slope.
#include <algorithm>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params&) {
    if (in.size() < 2) throw Error("takes x and at least one weight chunk, got " + std::to_string(in.size()) + " inputs");
    expect_f32(in);
    const Shape& x = in[0].shape;
    if (x.empty()) throw Error("input must have at least one dimension");
    const Shape& w0 = in[1].shape;
    if (w0.size() < 2) throw Error("weight chunk must be [rows, ...] with at least 2 dims, got " + shape_str(w0));
    int64_t rows = 0;
    for (size_t i = 1; i < in.size(); ++i) {
        const Shape& w = in[i].shape;
        if (w.size() != w0.size() || !std::equal(w.begin() + 1, w.end(), w0.begin() + 1))
            throw Error("weight chunks " + shape_str(w0) + " and " + shape_str(w) + " differ after the first axis");
        if (w[0] == 0) throw Error("weight chunk " + std::to_string(i - 1) + " is empty");
        rows += w[0];
    }
    if (rows != x.back())
        throw Error("input " + shape_str(x) + " has " + std::to_string(x.back()) + " features but the weight chunks hold " +
                    std::to_string(rows) + " rows");
    Shape y(x.begin(), x.end() - 1);
    y.insert(y.end(), w0.begin() + 1, w0.end());
    return {y};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const HostTensor& x = *in[0];
    const int64_t K = x.shape.back();
    const int64_t M = K ? x.size() / K : 0;
    const int64_t N = numel(in[1]->shape) / in[1]->shape[0];
    const uint32_t act = uint32_t(p.get("act", kActNone));
    const float slope = float(p.get("slope", 0.01));
    std::vector<double> acc(static_cast<size_t>(N));
    for (int64_t m = 0; m < M; ++m) {
        std::fill(acc.begin(), acc.end(), 0.0);
        int64_t k = 0;
        for (size_t c = 1; c < in.size(); ++c)
            for (int64_t r = 0; r < in[c]->shape[0]; ++r, ++k) {
                double xv = x.data[size_t(m * K + k)];
                const float* row = in[c]->data.data() + r * N;
                for (int64_t n = 0; n < N; ++n) acc[size_t(n)] += xv * row[n];
            }
        for (int64_t n = 0; n < N; ++n) out[0]->data[size_t(m * N + n)] = apply_act(float(acc[size_t(n)]), act, slope);
    }
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const int64_t K = a.in[0].shape.back();
    const int64_t N = numel(a.in[1].shape) / a.in[1].shape[0];
    const int64_t M = numel(a.out[0].shape) / std::max<int64_t>(1, N);
    if (M == 0 || N == 0) return;
    // Up to 8 rows (a batch's touches) per workgroup share each weight load; their
    // X slabs share the shared memory.
    const uint32_t mb = uint32_t(std::min<int64_t>(M, 8));
    const int64_t row_blocks = (M + mb - 1) / mb;
    if (row_blocks > int64_t(d.max_workgroup_count[1]))
        throw Error(std::to_string(M) + " input rows exceed the device's workgroup count limit");
    to_u32(M * K, "input size");
    to_u32(M * N, "output size");
    const uint32_t local = elementwise_local_size(d);
    // 16-byte loads when rows split into whole vec4s (bindings are 16-byte aligned:
    // weights and arena offsets are aligned to at least 16).
    const uint32_t V = N % 4 == 0 ? 4 : 1;
    // X slab per row in shared memory: up to 1024 values (a paper-size chunk in one slab).
    const uint32_t tk = std::max(1u, std::min(1024u, d.max_shared_memory / (8 * mb)));
    // Where the device has subgroup shuffles and every chunk fits its texel limit
    // (param subgroup = 0 forces the slabs): X by shuffles, W as texels, 64
    // threads per workgroup so that the columns spread over cores.
    const uint32_t sg = std::max(1u, d.subgroup_size);
    const uint32_t slocal = subgroup_group_size(d);
    bool shuffle = shuffles_allowed(a);
    // Loop iterations of one invocation for the longest chunk: column blocks of its
    // grid-stride loop, each walking the chunk's rows (kLoopIterationBudget).
    const uint64_t span = uint64_t(grid_groups(uint64_t(N / V), slocal, d)) * slocal;  // columns per round
    const uint64_t col_rounds = (uint64_t(N / V) + span - 1) / span;
    for (size_t c = 1; c < a.in.size(); ++c) {
        const uint64_t rows_c = uint64_t(a.in[c].shape[0]);
        shuffle = shuffle && uint64_t(numel(a.in[c].shape) / V) <= d.max_texel_elements &&
                  col_rounds * ((rows_c + sg - 1) / sg * (1 + uint64_t(sg) * (1 + mb)) + 2 * mb) <= kLoopIterationBudget;
    }
    const rt::Pipeline& pipe = shuffle ? a.ctx.pipelines().get(rt::PipelineDesc{"disentangle_subgroup", 3, 36,
                                                                                {slocal, V, mb}, 0x2u})
                                       : pipeline(a.ctx, "disentangle", 3, 36, {local, V, tk, mb});
    const VkFormat wfmt = !shuffle ? VK_FORMAT_UNDEFINED : V == 4 ? VK_FORMAT_R32G32B32A32_SFLOAT : VK_FORMAT_R32_SFLOAT;
    uint32_t k_off = 0;
    for (size_t c = 1; c < a.in.size(); ++c) {
        const uint32_t rows = to_u32(a.in[c].shape[0], "weight chunk rows");
        to_u32(int64_t(rows) * N, "weight chunk size");
        struct { uint32_t N, K, k_off, Kc, accumulate, last, act; float slope; uint32_t M; } push{
            uint32_t(N), uint32_t(K), k_off, rows, c > 1 ? 1u : 0u, c + 1 == a.in.size() ? 1u : 0u,
            uint32_t(a.params.get("act", kActNone)), float(a.params.get("slope", 0.01)), uint32_t(M)};
        a.seq.dispatch(pipe,
                       {{a.in[0].view, rt::Access::Read}, {a.in[c].view, rt::Access::Read, wfmt},
                        {a.out[0].view, c > 1 ? rt::Access::ReadWrite : rt::Access::Write}},
                       &push, sizeof(push), grid_groups(uint64_t(N / V), shuffle ? slocal : local, d),
                       uint32_t(row_blocks));
        k_off += rows;
    }
}

}  // namespace

const OpDef op_disentangle{"disentangle", infer, cpu, gpu, 0, {"act", "slope", "subgroup"}};

}  // namespace vtloc::ops
