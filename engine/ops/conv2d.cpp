// conv2d: y = act(conv(x, w) + bias + residual) -> shaders/conv2d.comp.
// Inputs: x [N, Cin, H, W], w (layout below), then optional bias [Cout], then
// optional residual [N, Cout, OH, OW] (param residual = 1 says the last input is one).
// Params: stride or stride_h/stride_w (1), pad or pad_h/pad_w (0), act / slope
// (ops::Act, none), weight_layout (kConvOIHW = PyTorch's [Cout, Cin, KH, KW],
// or kConvIHWO = [Cin, KH, KW, Cout], which the GPU reads 4 channels at a time),
// texel (1: read inputs as texel buffers where the device allows; 0: storage
// buffers, the fallback, forced for tests), split (0: the device's choice of
// how many parts the input channels are summed in, see ConvTiles::ksplit; > 0:
// that many, forced for tests), c_group (0: the device's choice of ConvTiles::c_group;
// 1 to 8: that many, forced for tests).
#include "engine/ops/conv2d.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {

HostTensor conv_weight_to_ihwo(const HostTensor& w) {
    if (w.shape.size() != 4) throw Error("conv weight must be [Cout, Cin, KH, KW], got " + shape_str(w.shape));
    const int64_t co = w.shape[0], k = w.shape[1] * w.shape[2] * w.shape[3];
    HostTensor out({w.shape[1], w.shape[2], w.shape[3], co});
    for (int64_t o = 0; o < co; ++o)
        for (int64_t i = 0; i < k; ++i) out.data[size_t(i * co + o)] = w.data[size_t(o * k + i)];
    return out;
}

namespace {

struct ConvParams {
    int64_t sh, sw, ph, pw;
    uint32_t layout, act;
    float slope;
    bool residual;
    uint32_t c_group = 0;  // tests: 1-8 forces ConvTiles::c_group; 0: the device's choice
};

int64_t int_param(const Params& p, const std::string& name, const std::string& fallback, double dflt, int64_t lo) {
    double v = p.get(name, p.get(fallback, dflt));
    if (v != std::floor(v) || v < double(lo) || v > 1e6)
        throw Error(name + " must be an integer >= " + std::to_string(lo) + ", got " + std::to_string(v));
    return int64_t(v);
}

ConvParams conv_params(const Params& p) {
    ConvParams c{int_param(p, "stride_h", "stride", 1, 1), int_param(p, "stride_w", "stride", 1, 1),
                 int_param(p, "pad_h", "pad", 0, 0), int_param(p, "pad_w", "pad", 0, 0),
                 uint32_t(int_param(p, "weight_layout", "weight_layout", kConvOIHW, 0)),
                 uint32_t(int_param(p, "act", "act", kActNone, 0)), float(p.get("slope", 0.01)),
                 p.get("residual", 0) != 0};
    if (c.layout > kConvIHWO) throw Error("weight_layout must be 0 (OIHW) or 1 (IHWO)");
    if (c.act > kActSigmoid) throw Error("unknown activation code " + std::to_string(c.act));
    const int64_t cg = int_param(p, "c_group", "c_group", 0, 0);
    if (cg > 8) throw Error("c_group must be an integer from 0 to 8, got " + std::to_string(cg));
    c.c_group = uint32_t(cg);
    return c;
}

// Geometry from the input shapes; throws naming the mismatch.
ConvShape conv_shape(const Shape& x, const Shape& w, const ConvParams& c) {
    if (x.size() != 4) throw Error("input must be [N, C, H, W], got " + shape_str(x));
    if (w.size() != 4) throw Error("weight must have 4 dimensions, got " + shape_str(w));
    ConvShape s{};
    s.n = x[0], s.cin = x[1], s.h = x[2], s.w = x[3], s.sh = c.sh, s.sw = c.sw;
    const bool oihw = c.layout == kConvOIHW;
    s.cout = oihw ? w[0] : w[3];
    s.kh = oihw ? w[2] : w[1];
    s.kw = oihw ? w[3] : w[2];
    const int64_t wcin = oihw ? w[1] : w[0];
    if (wcin != s.cin)
        throw Error("input " + shape_str(x) + " has " + std::to_string(s.cin) + " channels but weight " +
                    shape_str(w) + (oihw ? " (OIHW)" : " (IHWO)") + " expects " + std::to_string(wcin));
    if (s.kh < 1 || s.kw < 1 || s.cout < 1) throw Error("weight " + shape_str(w) + " is empty");
    if (s.h + 2 * c.ph < s.kh || s.w + 2 * c.pw < s.kw)
        throw Error("kernel " + std::to_string(s.kh) + "x" + std::to_string(s.kw) + " is larger than the padded input " +
                    std::to_string(s.h + 2 * c.ph) + "x" + std::to_string(s.w + 2 * c.pw));
    s.oh = (s.h + 2 * c.ph - s.kh) / c.sh + 1;
    s.ow = (s.w + 2 * c.pw - s.kw) / c.sw + 1;
    return s;
}

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 2, 4);
    expect_f32(in);
    ConvParams c = conv_params(p);
    if (c.residual && in.size() < 3) throw Error("residual = 1 needs a residual input");
    ConvShape s = conv_shape(in[0].shape, in[1].shape, c);
    const bool bias = in.size() - (c.residual ? 1 : 0) == 3;
    if (bias && in[2].shape != Shape{s.cout})
        throw Error("bias " + shape_str(in[2].shape) + " does not match " + std::to_string(s.cout) + " output channels");
    Shape y{s.n, s.cout, s.oh, s.ow};
    if (c.residual && in.back().shape != y)
        throw Error("residual " + shape_str(in.back().shape) + " does not match the output " + shape_str(y));
    return {y};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    ConvParams c = conv_params(p);
    ConvShape s = conv_shape(in[0]->shape, in[1]->shape, c);
    const HostTensor* bias = in.size() - (c.residual ? 1 : 0) == 3 ? in[2] : nullptr;
    const HostTensor* res = c.residual ? in.back() : nullptr;
    const auto& x = in[0]->data;
    const auto& w = in[1]->data;
    auto widx = [&](int64_t co, int64_t ci, int64_t ky, int64_t kx) {
        return c.layout == kConvOIHW ? ((co * s.cin + ci) * s.kh + ky) * s.kw + kx
                                     : ((ci * s.kh + ky) * s.kw + kx) * s.cout + co;
    };
    for (int64_t n = 0; n < s.n; ++n)
        for (int64_t co = 0; co < s.cout; ++co)
            for (int64_t oy = 0; oy < s.oh; ++oy)
                for (int64_t ox = 0; ox < s.ow; ++ox) {
                    double acc = bias ? bias->data[size_t(co)] : 0.0;
                    for (int64_t ci = 0; ci < s.cin; ++ci)
                        for (int64_t ky = 0; ky < s.kh; ++ky) {
                            int64_t iy = oy * s.sh - c.ph + ky;
                            if (iy < 0 || iy >= s.h) continue;
                            for (int64_t kx = 0; kx < s.kw; ++kx) {
                                int64_t ix = ox * s.sw - c.pw + kx;
                                if (ix < 0 || ix >= s.w) continue;
                                acc += double(x[size_t(((n * s.cin + ci) * s.h + iy) * s.w + ix)]) *
                                       w[size_t(widx(co, ci, ky, kx))];
                            }
                        }
                    size_t o = size_t(((n * s.cout + co) * s.oh + oy) * s.ow + ox);
                    if (res) acc += res->data[o];
                    out[0]->data[o] = apply_act(float(acc), c.act, c.slope);
                }
}

// Every choice gpu() makes, from the device and the input shapes (scratch_bytes
// must make the same ones).
struct ConvPlan {
    ConvParams c;
    ConvShape s;
    bool vec4, texel, xvec4;
    ConvTiles t;
    uint32_t cper;  // input channels per part (t.ksplit parts)
    uint64_t outputs() const { return uint64_t(s.n) * s.cout * s.oh * s.ow; }
};

ConvPlan conv_plan(const rt::DeviceInfo& d, const std::vector<Shape>& in, const Params& params) {
    ConvPlan pl;
    pl.c = conv_params(params);
    pl.s = conv_shape(in[0], in[1], pl.c);
    pl.s.pw = pl.c.pw;
    pl.vec4 = pl.c.layout == kConvIHWO && pl.s.cout % 4 == 0;
    // Texel buffers unless a tensor has more elements than the device allows in one.
    pl.texel = params.get("texel", 1) != 0;
    for (const Shape& sh : in) pl.texel &= uint64_t(numel(sh)) <= d.max_texel_elements;
    // Input rows as whole vec4s when x has a whole number of them.
    pl.xvec4 = pl.texel && numel(in[0]) % 4 == 0;
    pl.t = choose_conv_tiles(d, pl.s, pl.vec4, pl.xvec4);
    // "split" (tests): that many parts on any device; 0: the device's choice.
    const int64_t split = int_param(params, "split", "split", 0, 0);
    if (split > 0) pl.t.ksplit = uint32_t(std::min<int64_t>(split, pl.s.cin));
    if (pl.c.c_group > 0) pl.t.c_group = pl.c.c_group;  // "c_group" (tests): that many on any device
    pl.cper = uint32_t((pl.s.cin + pl.t.ksplit - 1) / pl.t.ksplit);
    pl.t.ksplit = uint32_t((pl.s.cin + pl.cper - 1) / pl.cper);  // no empty part
    return pl;
}

uint64_t scratch_bytes(const rt::DeviceInfo& d, const std::vector<Shape>& in, const Params& params) {
    const ConvPlan pl = conv_plan(d, in, params);
    return pl.t.ksplit > 1 ? uint64_t(pl.t.ksplit) * pl.outputs() * 4 : 0;
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    std::vector<Shape> shapes;
    for (const GpuTensor& t : a.in) shapes.push_back(t.shape);
    const ConvPlan pl = conv_plan(d, shapes, a.params);
    const ConvParams& c = pl.c;
    const ConvShape& s = pl.s;
    const ConvTiles& t = pl.t;
    const bool vec4 = pl.vec4, texel = pl.texel, xvec4 = pl.xvec4, split = t.ksplit > 1;
    const uint32_t wmode = c.layout == kConvOIHW ? 0 : vec4 ? 2 : 1;
    // The shader indexes with 32-bit signed offsets into x.
    to_u32(numel(a.in[0].shape) * 2, "conv input size (x2)");
    to_u32(numel(a.in[1].shape), "conv weight size");
    to_u32(int64_t(pl.outputs()) * t.ksplit, "conv output size (times its parts)");
    if (split && a.scratch.size < uint64_t(t.ksplit) * pl.outputs() * 4)
        throw Error("conv2d: its scratch is smaller than its " + std::to_string(t.ksplit) + " parts need");
    struct {
        uint32_t cin, h, w, cout, oh, ow;
        int32_t pad_h, pad_w;
        uint32_t bx, by, cb, lanes;
        float slope;
        int32_t xq;
        uint32_t part_lanes, cper, total;
    } push{uint32_t(s.cin), uint32_t(s.h), uint32_t(s.w), uint32_t(s.cout), uint32_t(s.oh), uint32_t(s.ow),
           int32_t(c.ph), int32_t(c.pw),
           uint32_t((s.ow + t.c - 1) / t.c), uint32_t((s.oh + t.r - 1) / t.r), uint32_t((s.cout + t.tm - 1) / t.tm),
           0, c.slope, int32_t(numel(a.in[0].shape) / 4), 0, pl.cper, uint32_t(pl.outputs())};
    push.part_lanes = to_u32(s.n * int64_t(push.bx) * push.by * push.cb, "conv invocations");
    push.lanes = to_u32(int64_t(push.part_lanes) * t.ksplit, "conv invocations (times its parts)");
    const bool bias = a.in.size() - (c.residual ? 1 : 0) == 3;
    // Absent bias / residual: the input fills the binding; the shader never reads it.
    const rt::BufferView& bv = bias ? a.in[2].view : a.in[0].view;
    const rt::BufferView& rv = c.residual ? a.in.back().view : a.in[0].view;
    // Split: the parts go to scratch, and the epilogue waits for the second pass.
    const rt::BufferView yv = split ? a.scratch : a.out[0].view;
    const bool epi_bias = bias && !split, epi_res = c.residual && !split;
    // Outputs (and the residual) 4 at a time when every block's row segment starts on a vec4.
    const bool yvec4 = texel && s.ow % 4 == 0 && t.c % 4 == 0 && (!split || pl.outputs() % 4 == 0);
    const VkFormat f1 = texel ? VK_FORMAT_R32_SFLOAT : VK_FORMAT_UNDEFINED;
    const VkFormat f4 = texel && vec4 ? VK_FORMAT_R32G32B32A32_SFLOAT : f1;
    const VkFormat fx4 = xvec4 ? VK_FORMAT_R32G32B32A32_SFLOAT : f1;
    const VkFormat fr4 = yvec4 && epi_res ? VK_FORMAT_R32G32B32A32_SFLOAT : f1;
    rt::PipelineDesc desc{texel ? "conv2d" : "conv2d_ssbo", 9, sizeof(push),
                          {t.local, t.tm, t.r, t.c, uint32_t(s.kh), uint32_t(s.kw), uint32_t(s.sh), uint32_t(s.sw),
                           wmode, split ? 0u : c.act, epi_bias ? 1u : 0u, epi_res ? 1u : 0u, s.cout < int64_t(t.tm) ? 1u : 0u,
                           xvec4 ? 1u : 0u, t.kh_block, t.x_shift, yvec4 ? 1u : 0u, t.ksplit, t.c_group},
                          texel ? 0x15fu : 0u};
    const rt::Pipeline& pipe = a.ctx.pipelines().get(desc);
    const uint64_t groups = (uint64_t(push.lanes) + t.local - 1) / t.local;
    const uint32_t gx = uint32_t(std::min<uint64_t>(groups, d.max_workgroup_count[0]));
    const uint64_t gy = (groups + gx - 1) / gx;
    if (gy > d.max_workgroup_count[1]) throw Error("conv output is too large for one dispatch");
    const rt::Access rd = rt::Access::Read;
    a.seq.dispatch(pipe,
                   {{a.in[0].view, rd, f1}, {a.in[1].view, rd, f1}, {a.in[1].view, rd, f4}, {bv, rd, f1},
                    {rv, rd, f1}, {yv, rt::Access::Write}, {a.in[0].view, rd, fx4},
                    {yv, rt::Access::Write}, {rv, rd, fr4}},
                   &push, sizeof(push), gx, uint32_t(gy));
    if (!split) return;
    struct {
        uint32_t total, cout, plane;
        float slope;
    } sum{uint32_t(pl.outputs()), uint32_t(s.cout), uint32_t(s.oh * s.ow), c.slope};
    const uint32_t local = fill_local_size(d, pl.outputs());
    const rt::Pipeline& add = a.ctx.pipelines().get(
        {"conv2d_split_sum", 4, sizeof(sum), {local, t.ksplit, c.act, bias ? 1u : 0u, c.residual ? 1u : 0u}});
    const uint64_t sum_groups = std::min<uint64_t>((pl.outputs() + local - 1) / local, d.max_workgroup_count[0]);
    a.seq.dispatch(add, {{a.scratch, rd}, {bias ? bv : a.scratch, rd}, {c.residual ? rv : a.scratch, rd}, {a.out[0].view, rt::Access::Write}},
                   &sum, sizeof(sum), uint32_t(sum_groups));
}

}  // namespace

const OpDef op_conv2d{"conv2d", infer, cpu, gpu, 0,
                      {"stride", "stride_h", "stride_w", "pad", "pad_h", "pad_w", "weight_layout", "act", "slope", "residual", "texel",
                       "split", "c_group"},
                      nullptr, scratch_bytes};

}  // namespace vtloc::ops
