// group_linear: one PointNet++ MLP layer (1x1 conv with BatchNorm folded, then
// act) -> shaders/point_mlp.comp. The weight is input-major W^T [K, N] (4 output
// channels = one vec4), and activations between layers are channel-major [C, M]
// (4 rows = one vec4) or point-major [M, C] (4 channels = one vec4: params
// point_major / x_point_major, the point encoder's choice), so the shader reads
// everything as vec4s. Param texel
// (default 1): read activations and the cloud as texel buffers where the device allows;
// then param weights (GroupLinear::Weights, default 0) says how the weights, which
// every lane of a workgroup reads at the same address, reach the lanes:
//   0: shared by subgroup shuffles from a texel buffer (point_mlp_shfl.comp), where the
//      device has shuffles and the matrix fits its texel-buffer limit; else as 1;
//   1: from a uniform buffer (point_mlp_ubo.comp), where the matrix fits the device's
//      uniform range; else as 2;
//   2: from a storage buffer (point_mlp.comp), a broadcast on GPUs but a loop over the
//      lanes on a CPU driver (docs/performance.md "On CPUs without AVX-512, measured").
// Param `in` picks the input (optional features always last):
//   0: x^T [K, M] (channel-major, the previous layer's output), or x [M, K] with
//      param x_point_major: [x^T, W^T, bias (, idx I32 [M / group, group] with pad and max)]
//   1: grouping fused (SPEC 2, as point_group): [points [P, D >= 3], centres [S, 3],
//      idx I32 [S, NS], W^T, bias (, features [P, DF])]; row m = s * NS + j is
//      [features of q from column feat_begin, xyz of q - centre s], q = idx[s, j].
//   2: group all: [xyz [M, 3], W^T, bias (, features [M, C])]; row m is
//      [xyz of m, features of m] (xyz first, not centred).
//   3: per point: [points [M, D >= 3], W^T, bias (, features [M, DF])]; row m is
//      [features of m from column feat_begin, xyz of m] (a set-abstraction
//      layer's columns, not centred: sa_gather subtracts the centre's part).
// Param hidden (GroupLinear::Hidden, with in = 1): the layer's input x^T is a first
// layer computed in registers from the ball rows, never stored (K % 4 == 0):
//   1: [points, centres, idx, W0^T [CF + 3, K], b0 [K], W^T, bias (, features)]:
//      act(row W0^T + b0) of the gathered row (at most 4 feature columns);
//   2: [U [P, K], centres, idx, W0^T [K0 >= 3, K], W^T, bias]: act(U[q] - W0^T's
//      last 3 rows . centre), U = the same layer per source point (in = 3,
//      point_major; sa_gather's arithmetic, without its stored output).
// Param point_major = 1 (not with max): the output is [M, N] instead of [N, M].
// Param x_point_major = 1 (in = 0): x is [M, K] (a point_major output) instead of x^T.
// Param pad = 1 (GroupLinear::skip_padding): a row j > 0 of a ball whose index equals
// the ball's first (SPEC 2's padding: row 0's input again) is work to skip. A max
// leaves such rows out (the same max wherever they repeat row 0, and what makes
// skipping safe); a plain output (in = 1 only) holds anything in them. in = 1 takes the
// ball from its idx; a max over in = 0 rows takes it as a last input, idx I32 [M / group,
// group]. A max after a plain output with pad must take it too. The point encoder sets it
// on the max and on the gathering layer right before it. Param row_blocks = 1 (tests):
// a plain output with pad runs one invocation per row block on any device (see gpu()).
// Param max = 1: the output is the max over each group of NS consecutive rows,
// point-major [M / NS, N] (NS = the ball size for in = 1, param `group` otherwise);
// else channel-major [N, M] (point_major: [M, N]). Params act, slope as linear's. Param tile
// (GroupLinear::Tile): 1 = 16 x 32, 2 = 8 x 32, big-layer tiles, whatever the layer
// and device (tests). Param rows_in_x = 1: row blocks along x, channel blocks along
// y (tests; the default is the reverse, see gpu()). Param fill = W (tests): the tiles
// a GPU would shrink to so as to offer W workgroups, on any device (see gpu()). Param
// parts = P (tests; a max on the vote shader, P a power of two <= the subgroup size):
// P lanes per group, as a GPU's rule may choose; larger P is refused at the dispatch.
#include <algorithm>
#include <limits>

#include "base/error.h"
#include "engine/ops/build.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"
#include "engine/ops/point_common.h"
#include "runtime/memory.h"

namespace vtloc::ops {
namespace {

using Weights = GroupLinear::Weights;

struct Layout {
    int mode = 0;
    bool max = false;
    GatherShape g;  // in = 1 (in = 2, 3: P = M; in = 2: D = 3, DF = C)
    int64_t M = 0, K = 0, N = 0, NS = 1;
    size_t w = 1;   // index of W^T among the inputs
    bool feat = false;
    int hidden = 0;       // in = 1: GroupLinear::Hidden; K is W0^T's width
    bool point_major = false;
    bool x_point_major = false;  // in = 0: x is [M, K]
    bool pad = false;     // param pad: ball padding skipped
};

// Input i is I32: a gather's ball, or a max's ball (pad) after x^T, W^T and bias.
bool index_input(const Params& p, size_t i) {
    const double mode = p.get("in", 0);
    return (mode == 1 && i == 2) || (mode == 0 && p.get("pad", 0) != 0 && i == 3);
}

Layout layout_of(const std::vector<TensorDesc>& in, const Params& p) {
    Layout l;
    l.mode = p.has("in") ? int(int_param(p, "in", 0, 3)) : 0;
    if (p.has("weights")) int_param(p, "weights", 0, 2);  // GroupLinear::Weights: named at graph build
    if (p.has("tile")) int_param(p, "tile", 0, 2);
    if (p.has("parts")) {
        pow2_param(p, "parts", 1, 64);
        if (p.get("max", 0) == 0) throw Error("parts is for a max over rows (max = 1)");
    }
    l.max = p.get("max", 0) != 0;
    l.hidden = p.has("hidden") ? int(int_param(p, "hidden", 0, 2)) : 0;
    if (l.hidden != 0 && l.mode != 1) throw Error("hidden = " + std::to_string(l.hidden) + " needs gathered rows (in = 1)");
    l.point_major = p.get("point_major", 0) != 0;
    if (l.point_major && l.max) throw Error("point_major = 1 is for plain outputs (a max is point-major already)");
    l.pad = p.get("pad", 0) != 0;
    if (l.pad && !(l.mode == 1 || (l.mode == 0 && l.max)))
        throw Error("pad = 1 needs ball rows (in = 1) or a max over rows with their ball (in = 0, max = 1)");
    l.x_point_major = p.get("x_point_major", 0) != 0;
    if (l.x_point_major && l.mode != 0) throw Error("x_point_major = 1 is for a previous layer's rows (in = 0)");
    for (size_t i = 0; i < in.size(); ++i)
        if (in[i].type != (index_input(p, i) ? ElemType::I32 : ElemType::F32))
            throw Error("input " + std::to_string(i) + " has the wrong element type");
    if (l.mode == 1) {
        const size_t base = l.hidden == 1 ? 7 : l.hidden == 2 ? 6 : 5;
        expect_input_count(in, base, l.hidden == 2 ? base : base + 1);  // hidden 2: U holds the features
        l.feat = in.size() == base + 1;
        l.g = gather_shape(in[0], in[1], in[2], l.feat ? &in[base] : nullptr, p);
        l.M = l.g.rows(), l.K = l.g.K(), l.NS = l.g.NS, l.w = base - 2;
        if (l.hidden == 2) {
            const Shape& w0 = in[3].shape;
            const int64_t k = in[0].shape[1];
            if (k % 4 != 0) throw Error("U " + shape_str(in[0].shape) + ": its width is not a multiple of 4");
            if (w0.size() != 2 || w0[0] < 3 || w0[1] != k)
                throw Error("hidden weight " + shape_str(w0) + " must be input-major [K0 >= 3, " + std::to_string(k) + "]");
            l.K = k;
            l.g.CF = w0[0] - 3;  // the row of W0^T where xyz begins (the shader reads it as CF)
        }
        if (l.hidden == 1) {
            const Shape &w0 = in[3].shape, &b0 = in[4].shape;
            if (w0.size() != 2 || w0[0] != l.K)
                throw Error("hidden weight " + shape_str(w0) + " must be input-major [" + std::to_string(l.K) + ", width]");
            if (w0[1] % 4 != 0) throw Error("hidden width " + std::to_string(w0[1]) + " is not a multiple of 4");
            if (l.g.CF > 4) throw Error("hidden = 1 takes at most 4 feature columns, got " + std::to_string(l.g.CF));
            if (b0 != Shape{w0[1]}) throw Error("hidden bias " + shape_str(b0) + " does not match " + shape_str(w0));
            l.K = w0[1];
        }
    } else if (l.mode == 3) {
        expect_input_count(in, 3, 4);
        const Shape& x = in[0].shape;
        if (x.size() != 2 || x[1] < 3) throw Error("points must be [M, D >= 3], got " + shape_str(x));
        l.feat = in.size() == 4;
        l.M = l.g.P = x[0], l.g.D = x[1];
        if (l.feat) {
            if (in[3].shape.size() != 2 || in[3].shape[0] != l.M)
                throw Error("features " + shape_str(in[3].shape) + " must have one row per point (" + std::to_string(l.M) + ")");
            l.g.DF = in[3].shape[1];
            l.g.FB = p.has("feat_begin") ? int_param(p, "feat_begin", 0, l.g.DF) : 0;
            l.g.CF = l.g.DF - l.g.FB;
        }
        l.K = l.g.CF + 3;
        if (l.max) l.NS = int_param(p, "group", 1, std::max<int64_t>(1, l.M));
    } else {
        expect_input_count(in, l.pad ? 4 : 3, l.mode == 2 || l.pad ? 4 : 3);
        const Shape& x = in[0].shape;
        if (x.size() != 2 || (l.mode == 2 && x[1] != 3))
            throw Error(std::string(l.mode == 2              ? "xyz must be [M, 3]"
                                    : l.x_point_major ? "x must be point-major [M, K]"
                                                      : "x must be channel-major [K, M]") +
                        ", got " + shape_str(x));
        if (l.mode == 0) {
            l.K = x[l.x_point_major ? 1 : 0], l.M = x[l.x_point_major ? 0 : 1];
        } else {
            l.feat = in.size() == 4;
            l.M = x[0];
            l.g.P = l.M, l.g.D = 3;
            if (l.feat) {
                if (in[3].shape.size() != 2 || in[3].shape[0] != l.M)
                    throw Error("features " + shape_str(in[3].shape) + " must have one row per point (" + std::to_string(l.M) + ")");
                l.g.DF = l.g.CF = in[3].shape[1];
            }
            l.K = 3 + l.g.CF;
        }
        if (l.max) l.NS = int_param(p, "group", 1, std::max<int64_t>(1, l.M));
        if (l.pad && in[3].shape != Shape{l.M / l.NS, l.NS})
            throw Error("ball " + shape_str(in[3].shape) + " must be [" + std::to_string(l.M / l.NS) + ", " +
                        std::to_string(l.NS) + "]: one index per row");
    }
    if (l.M == 0) throw Error("no rows");
    if (l.M % l.NS != 0) throw Error(std::to_string(l.M) + " rows do not split into groups of " + std::to_string(l.NS));
    const Shape &w = in[l.w].shape, &b = in[l.w + 1].shape;
    if (w.size() != 2 || w[0] != l.K)
        throw Error("weight " + shape_str(w) + " must be input-major [" + std::to_string(l.K) + ", out]");
    l.N = w[1];
    if (b != Shape{l.N}) throw Error("bias " + shape_str(b) + " does not match weight " + shape_str(w));
    to_u32(l.M * std::max(l.K, l.N), "layer size");
    to_u32(std::max(l.g.P * l.g.D, l.g.P * l.g.DF), "point array size");
    return l;
}

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    Layout l = layout_of(in, p);
    return {TensorDesc{l.max ? Shape{l.M / l.NS, l.N} : l.point_major ? Shape{l.M, l.N} : Shape{l.N, l.M}}};
}

// b[n] + x . column n of the input-major weight w [x.size(), N], in double.
double dot(const std::vector<float>& x, const HostTensor& w, const HostTensor& b, int64_t N, int64_t n) {
    double acc = b.data[size_t(n)];
    for (size_t k = 0; k < x.size(); ++k) acc += double(x[k]) * w.data[k * size_t(N) + size_t(n)];
    return acc;
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    std::vector<TensorDesc> d;
    for (const HostTensor* t : in) d.push_back({t->shape, t->type});
    const Layout l = layout_of(d, p);
    const HostTensor &w = *in[l.w], &b = *in[l.w + 1];
    const HostTensor* feat = l.feat ? in.back() : nullptr;
    const uint32_t act = uint32_t(p.get("act", kActNone));
    const float slope = float(p.get("slope", 0.01));
    const int64_t K0 = l.hidden == 1 ? in[3]->shape[0] : l.hidden == 2 ? 0 : l.K;  // the gathered row's width
    std::vector<float> row(static_cast<size_t>(K0)), hid(static_cast<size_t>(l.K));
    if (l.max) std::fill(out[0]->data.begin(), out[0]->data.end(), -std::numeric_limits<float>::infinity());
    const HostTensor* ball = l.mode == 1 ? in[2] : l.pad ? in[3] : nullptr;
    for (int64_t m = 0; m < l.M; ++m) {
        if (l.pad && l.max && padding_row(*ball, m, l.NS)) continue;  // a plain output computes it: any value will do
        for (int64_t k = 0; k < K0; ++k)
            row[size_t(k)] = l.mode == 1   ? gather_value(*in[0], *in[1], *in[2], feat, l.g, m, k)
                             : l.mode == 2 ? (k < 3 ? in[0]->data[size_t(3 * m + k)] : feat->data[size_t(m * l.g.CF + k - 3)])
                             : l.mode == 3 ? (k < l.g.CF ? feat->data[size_t(m * l.g.DF + l.g.FB + k)]
                                                         : in[0]->data[size_t(m * l.g.D + k - l.g.CF)])
                             : l.x_point_major ? in[0]->data[size_t(m * l.K + k)]
                                               : in[0]->data[size_t(k * l.M + m)];
        if (l.hidden == 2) {  // U[q] less the centre's share, as sa_gather gives it
            const int32_t q = ball_point(*in[2], m, l.g.P);
            const float* c = &in[1]->data[size_t(3 * (m / l.NS))];
            for (int64_t n = 0; n < l.K; ++n)
                hid[size_t(n)] =
                    apply_act(float(in[0]->data[size_t(q * l.K + n)] - centre_share(*in[3], l.g.CF, l.K, n, c)), act, slope);
        }
        if (l.hidden == 1)  // the hidden layer, as a group_linear of its own would give it
            for (int64_t n = 0; n < l.K; ++n) hid[size_t(n)] = apply_act(float(dot(row, *in[3], *in[4], l.K, n)), act, slope);
        const std::vector<float>& x = l.hidden != 0 ? hid : row;
        for (int64_t n = 0; n < l.N; ++n) {
            const float v = apply_act(float(dot(x, w, b, l.N, n)), act, slope);
            if (l.max) {
                float& o = out[0]->data[size_t((m / l.NS) * l.N + n)];
                o = std::max(o, v);
            } else {
                out[0]->data[size_t(l.point_major ? m * l.N + n : n * l.M + m)] = v;
            }
        }
    }
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    std::vector<TensorDesc> ds;
    for (size_t i = 0; i < a.in.size(); ++i) ds.push_back({a.in[i].shape, index_input(a.params, i) ? ElemType::I32 : ElemType::F32});
    const Layout l = layout_of(ds, a.params);
    // The activations / cloud (bindings 0, 1), centres and indices (6, 7) and
    // features (8, 9) are read as texel buffers where the device's texel-buffer
    // limit allows (param texel = 0 forces storage buffers); bindings 1 and 9 are
    // the same tensors as vec4s.
    const GpuTensor& src = a.in[0];
    const GpuTensor& fsrc = l.feat ? a.in.back() : src;  // without features: any texel-able buffer
    const GpuTensor& bias = a.in[l.w + 1];  // also the filler of bindings the mode does not read
    const GpuTensor& centres = l.mode == 1 ? a.in[1] : bias;
    const GpuTensor& index = l.mode == 1 ? a.in[2] : l.pad ? a.in[3] : bias;
    bool texel = a.params.get("texel", 1) != 0;
    // hidden: W0^T and b0 (bindings 10, 11, as vec4s); else the bias fills them.
    const GpuTensor& w0 = l.hidden != 0 ? a.in[3] : bias;
    const GpuTensor& b0 = l.hidden == 1 ? a.in[4] : bias;
    for (const GpuTensor* t : {&src, &fsrc, &centres, &index, &bias, &w0})
        texel = texel && uint64_t(numel(t->shape)) <= d.max_texel_elements;
    auto fmt = [&](const GpuTensor& t, bool vec4) {
        if (!texel) return VK_FORMAT_UNDEFINED;
        return vec4 && numel(t.shape) % 4 == 0 ? VK_FORMAT_R32G32B32A32_SFLOAT : VK_FORMAT_R32_SFLOAT;
    };
    const Weights wp = group_linear_weight_path(d, l.K, l.N, texel, Weights(a.params.get("weights", 0)), a.in[l.w].view.offset);
    // TM x TN accumulators per invocation, both multiples of 4 (the shader's vec4
    // granularity), fewer channels for narrow layers. GPUs: 8 x 16 (registers).
    // CPU devices run a subgroup as one SIMD stream and pay for every texel fetch
    // (a call that spills the live vector registers), so big layers (rows for 64
    // invocations, 1e8 multiply-adds) take a bigger tile. History: 16 x 32 was
    // chosen first, measured on lavapipe (AVX2) against 8 x 16, 8 x 24,
    // 8 x 32, 12 x 32, 16 x 16, 16 x 48, 16 x 64 and 32 x 32: 10-25 % faster on
    // the paper's SA layers, but 2x slower on a 64-row layer, and its unrolled
    // shader compiles for ~2 s, which small layers never earn back (bench/README.md).
    // 8 x 32 measured faster later: with 32 vector registers (AVX-512VL: 12-17 % on
    // three of those layers), and once weights were fetched as vec4s and channel
    // blocks ran back to back, with 16 too (the same host with Mesa's JIT held to
    // AVX2: the point encoder 20 % faster), so it is the big-layer tile on every CPU device;
    // param tile 1 keeps 16 x 32 for tests and comparisons (bench/README.md).
    // Param fill (tests): a GPU's rule below with that many workgroups to offer, on any device.
    const int64_t fill = int64_t(a.params.get("fill", 0));
    const bool cpu_rule = d.type == VK_PHYSICAL_DEVICE_TYPE_CPU && fill == 0;
    const int64_t big_blocks = l.max ? l.M / l.NS : (l.M + 15) / 16;
    const int tile = int(a.params.get("tile", 0));
    const bool big = tile != 0 || (cpu_rule && big_blocks >= 64 && double(l.M) * l.K * l.N >= 1e8);
    uint32_t TM = big && tile == 1 ? 16 : 8;
    uint32_t TN = big && l.N >= 32 ? 32 : l.N >= 16 ? 16 : l.N > 4 ? 8 : 4;
    // A plain output with pad on a CPU device: one invocation per ball, pooling the
    // chunks of a subgroup's balls (point_mlp.glsl POOL). A GPU keeps one invocation
    // per row block: 16x fewer invocations would leave it idle. Param row_blocks
    // (tests) keeps the GPU's way on any device.
    const bool pool = l.pad && !l.max && wp == Weights::Shuffle && cpu_rule && a.params.get("row_blocks", 0) == 0;
    // A max's groups each take PARTS lanes (point_mlp.glsl): the vote shader's only.
    uint32_t parts = uint32_t(a.params.get("parts", 1));
    const bool can_part = l.max && wp == Weights::Shuffle;
    if (parts > 1 && !can_part)
        throw Error("parts = " + std::to_string(parts) + " needs a max on the subgroup-shuffle shader: not this layer or device");
    auto chunks = [&] { return uint32_t((l.NS + TM - 1) / TM); };  // TM-row blocks per group
    auto blocks_of = [&](uint32_t tm) {
        return l.max ? uint64_t(l.M / l.NS) * parts : pool ? uint64_t(l.M / l.NS) : (uint64_t(l.M) + tm - 1) / tm;
    };
    // Up to 64 invocations (whole subgroups), fewer when there are few blocks:
    // spare invocations redo the last block.
    uint32_t L = std::min(64u, elementwise_local_size(d));
    const uint32_t sg = std::max(1u, d.subgroup_size);
    while (L > sg && L / 2 >= blocks_of(TM)) L /= 2;
    // GPUs: a layer of few rows or channels (SA3, the SA2 maxes) must still give every
    // compute unit work (rt::fill_workgroups). Workgroups shrink to one subgroup first (the
    // same invocations, spread wider), then the channel block to 8 and 4, then the row
    // block to 4 (a max's rows are a loop: its block stays).
    if (!cpu_rule) {
        const uint64_t want = fill > 0 ? uint64_t(fill) : rt::fill_workgroups(d);
        auto groups = [&] { return (blocks_of(TM) + L - 1) / L * ((uint64_t(l.N) + TN - 1) / TN); };
        while (groups() < want) {
            if (L / 2 >= sg && (L / 2) % sg == 0) L /= 2;
            else if (TN > 4 && !big) TN /= 2;
            else if (TM > 4 && !big && !l.max) TM = 4;
            else if (can_part && !a.params.has("parts") && parts * 2 <= std::min(sg, L) && parts * 2 <= chunks()) parts *= 2;
            else break;
        }
    }
    // A group's lanes must share a subgroup: at most its size, nor the workgroup's where
    // that is smaller (a 128-lane subgroup, 64 invocations).
    if (parts > std::min(sg, L))
        throw Error("parts = " + std::to_string(parts) + " is over this layer's " + std::to_string(std::min(sg, L)) +
                    " lanes a subgroup (the subgroup size " + std::to_string(sg) + ", the workgroup " + std::to_string(L) + ")");
    const uint64_t blocks = blocks_of(TM);
    const uint64_t gx = (blocks + L - 1) / L, gy = (uint64_t(l.N) + TN - 1) / TN;
    // Channel blocks along x, so that the workgroups a driver runs one after the
    // other (x first on lavapipe) read the same input rows while they are still in
    // cache, instead of every channel block streaming all rows from memory: the
    // paper's SA1 and SA2 max layers re-read 25 and 8 MB inputs 4 and 8 times.
    // Param rows_in_x (tests) or a row count past the y limit keeps rows along x.
    const bool cb_first =
        a.params.get("rows_in_x", 0) == 0 && gx <= d.max_workgroup_count[1] && gy <= d.max_workgroup_count[0];
    if (!cb_first && (gx > d.max_workgroup_count[0] || gy > d.max_workgroup_count[1]))
        throw Error("point-MLP layer of " + std::to_string(l.M) + " rows needs more workgroups than the device allows");
    // vec4 reads of x: 4 rows of a channel (channel-major), or 4 channels of a row.
    const bool avec4 = l.mode == 0 && (l.x_point_major ? l.K % 4 == 0 : l.M % 4 == 0 && (!l.max || l.NS % 4 == 0));
    const bool fvec4 = l.feat && l.g.DF % 4 == 0 && l.g.FB % 4 == 0;
    const bool wvec4 = l.N % 4 == 0;  // weight rows of whole vec4s: spec constant WVEC4 and binding 2's format
    struct { uint32_t M, N, K, NS; float slope; uint32_t P, D, DF, FB, CF, blocks, chunks; } push{
        uint32_t(l.M), uint32_t(l.N), uint32_t(l.K), uint32_t(l.NS), float(a.params.get("slope", 0.01)),
        uint32_t(l.g.P), uint32_t(l.g.D), uint32_t(l.g.DF), uint32_t(l.g.FB), uint32_t(l.g.CF), uint32_t(blocks),
        chunks()};
    // WVECS (9) only where the shader declares it: elsewhere a weight-shape-dependent
    // constant would compile one pipeline per layer shape for nothing.
    std::vector<uint32_t> spec{L, TM, TN, uint32_t(l.mode), l.max, uint32_t(a.params.get("act", kActNone)), avec4, fvec4,
                               wvec4, wp == Weights::Uniform ? uint32_t(l.K * l.N / 4) : 1u, d.subgroup_size,
                               !l.max && !l.point_major && l.M % 4 == 0 && (!pool || l.NS % 4 == 0), uint32_t(l.hidden),
                               l.point_major, cb_first, l.pad, l.x_point_major, pool, parts};
    const char* shader = wp == Weights::Shuffle ? "point_mlp_shfl" : wp == Weights::Uniform ? "point_mlp_ubo"
                         : texel                ? "point_mlp"
                                                : "point_mlp_ssbo";
    const uint32_t texels = texel ? (wp == Weights::Shuffle ? 0xFC7u : 0xFC3u) : 0u;
    const rt::PipelineDesc desc{shader, 12, sizeof(push), spec, texels, wp == Weights::Uniform ? 0x8u : 0u};
    const rt::BufferView& wv = a.in[l.w].view;
    const rt::Access R = rt::Access::Read;
    const VkFormat f32 = texel ? VK_FORMAT_R32_SFLOAT : VK_FORMAT_UNDEFINED;
    a.seq.dispatch(a.ctx.pipelines().get(desc),
                   {{src.view, R, fmt(src, false)}, {src.view, R, fmt(src, true)},
                    {wv, R, wp != Weights::Shuffle ? VK_FORMAT_UNDEFINED
                            : wvec4            ? VK_FORMAT_R32G32B32A32_SFLOAT
                                               : VK_FORMAT_R32_SFLOAT},
                    {wv, R},
                    {bias.view, R}, {a.out[0].view, rt::Access::Write},
                    {centres.view, R, f32}, {index.view, R, texel ? VK_FORMAT_R32_SINT : VK_FORMAT_UNDEFINED},
                    {fsrc.view, R, fmt(fsrc, false)}, {fsrc.view, R, fmt(fsrc, true)},
                    {w0.view, R, fmt(w0, l.hidden != 0)}, {b0.view, R, fmt(b0, l.hidden == 1)}},
                   &push, sizeof(push), uint32_t(cb_first ? gy : gx), uint32_t(cb_first ? gx : gy));
}

// A plain output's padding rows (param pad) are unspecified: the reference's values there.
void take_unspecified(const std::vector<const HostTensor*>& in, const Params& p, const HostTensor& ref, HostTensor& out) {
    if (p.get("pad", 0) == 0 || p.get("max", 0) != 0 || in.size() < 3 || out.shape != ref.shape || out.shape.size() != 2) return;
    const HostTensor& ball = *in[2];
    const bool pm = p.get("point_major", 0) != 0;  // [M, N], else [N, M]
    const int64_t M = out.shape[pm ? 0 : 1], N = out.shape[pm ? 1 : 0], NS = ball.shape.size() == 2 ? ball.shape[1] : 0;
    if (NS <= 0 || ball.size() != M) return;
    for (int64_t m = 0; m < M; ++m)
        if (padding_row(ball, m, NS))
            for (int64_t n = 0; n < N; ++n) {
                const size_t e = size_t(pm ? m * N + n : n * M + m);
                out.data[e] = ref.data[e];
            }
}

}  // namespace

const OpDef op_group_linear{"group_linear", infer, cpu, gpu, 0,
                            {"in", "feat_begin", "max", "group", "act", "slope", "texel", "weights", "tile", "hidden", "point_major",
                             "x_point_major", "rows_in_x", "pad", "row_blocks", "fill", "parts"},
                            take_unspecified};

GroupLinear::Weights group_linear_weight_path(const rt::DeviceInfo& d, int64_t K, int64_t N, bool texel,
                                              GroupLinear::Weights want, uint64_t offset) {
    using W = GroupLinear::Weights;
    const uint64_t bytes = uint64_t(K * N) * 4;
    // point_mlp_shfl.comp also votes (param pad): shuffles without votes are rare enough to fall back.
    if (want == W::Shuffle && texel && has_subgroup_shuffles(d) && (d.subgroup_ops & VK_SUBGROUP_FEATURE_VOTE_BIT) &&
        uint64_t(K * N) <= d.max_texel_elements)
        return W::Shuffle;
    // std140 vec4s: N % 4 == 0; the binding's offset must meet the device's alignment.
    if (want != W::Storage && texel && N % 4 == 0 && bytes <= d.max_uniform_range &&
        offset % std::max<uint64_t>(1, d.uniform_offset_alignment) == 0)
        return W::Uniform;
    return W::Storage;
}

// W [N, K] (PyTorch Linear / squeezed 1x1 conv) -> W^T [K, N], group_linear's layout.
HostTensor point_weight_kn(const HostTensor& w) {
    if (w.shape.size() < 2) throw Error("point_weight_kn: weight must be [out, in, ...], got " + shape_str(w.shape));
    const int64_t N = w.shape[0], K = w.size() / std::max<int64_t>(1, N);
    HostTensor t({K, N});
    for (int64_t n = 0; n < N; ++n)
        for (int64_t k = 0; k < K; ++k) t.data[size_t(k * N + n)] = w.data[size_t(n * K + k)];
    return t;
}

}  // namespace vtloc::ops
