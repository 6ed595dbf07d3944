// max_pool2d: PyTorch MaxPool2d on [N, C, H, W] (dilation 1, floor mode) ->
//   shaders/max_pool2d.comp. Params: kernel or kernel_h/kernel_w (required),
//   stride or stride_h/stride_w (default: the kernel), pad or pad_h/pad_w (0, at
//   most half the kernel, as PyTorch requires), texel (1: read the input as a texel
//   buffer where the device allows; 0: as a storage buffer, the fallback).
// global_avg_pool: [N, C, H, W] -> [N, C, 1, 1], the mean of each plane
//   (AdaptiveAvgPool2d(1)) -> shaders/global_avg_pool.comp.
#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

struct PoolGeom {
    int64_t kh, kw, sh, sw, ph, pw, oh, ow;
};

int64_t int_param(const Params& p, const std::string& name, const std::string& fallback, double dflt, int64_t lo) {
    double v = p.get(name, p.get(fallback, dflt));
    if (v != std::floor(v) || v < double(lo) || v > 1e6)
        throw Error(name + " must be an integer >= " + std::to_string(lo) + ", got " + std::to_string(v));
    return int64_t(v);
}

PoolGeom pool_geom(const Shape& x, const Params& p) {
    if (x.size() != 4) throw Error("input must be [N, C, H, W], got " + shape_str(x));
    if (!p.has("kernel") && !(p.has("kernel_h") && p.has("kernel_w"))) throw Error("needs a kernel size");
    PoolGeom g{};
    g.kh = int_param(p, "kernel_h", "kernel", 0, 1);
    g.kw = int_param(p, "kernel_w", "kernel", 0, 1);
    g.sh = int_param(p, "stride_h", "stride", double(g.kh), 1);
    g.sw = int_param(p, "stride_w", "stride", double(g.kw), 1);
    g.ph = int_param(p, "pad_h", "pad", 0, 0);
    g.pw = int_param(p, "pad_w", "pad", 0, 0);
    if (2 * g.ph > g.kh || 2 * g.pw > g.kw) throw Error("padding must be at most half the kernel");
    if (x[2] + 2 * g.ph < g.kh || x[3] + 2 * g.pw < g.kw)
        throw Error("kernel " + std::to_string(g.kh) + "x" + std::to_string(g.kw) + " is larger than the padded input " +
                    std::to_string(x[2] + 2 * g.ph) + "x" + std::to_string(x[3] + 2 * g.pw));
    g.oh = (x[2] + 2 * g.ph - g.kh) / g.sh + 1;
    g.ow = (x[3] + 2 * g.pw - g.kw) / g.sw + 1;
    return g;
}

std::vector<TensorDesc> max_infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 1, 1);
    expect_f32(in);
    PoolGeom g = pool_geom(in[0].shape, p);
    return {Shape{in[0].shape[0], in[0].shape[1], g.oh, g.ow}};
}

void max_cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const Shape& x = in[0]->shape;
    PoolGeom g = pool_geom(x, p);
    const int64_t planes = x[0] * x[1], h = x[2], w = x[3];
    for (int64_t pl = 0; pl < planes; ++pl)
        for (int64_t oy = 0; oy < g.oh; ++oy)
            for (int64_t ox = 0; ox < g.ow; ++ox) {
                float m = -std::numeric_limits<float>::infinity();
                for (int64_t ky = 0; ky < g.kh; ++ky)
                    for (int64_t kx = 0; kx < g.kw; ++kx) {
                        int64_t iy = oy * g.sh - g.ph + ky, ix = ox * g.sw - g.pw + kx;
                        if (iy >= 0 && iy < h && ix >= 0 && ix < w)
                            m = std::max(m, in[0]->data[size_t((pl * h + iy) * w + ix)]);
                    }
                out[0]->data[size_t((pl * g.oh + oy) * g.ow + ox)] = m;
            }
}

void max_gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const Shape& x = a.in[0].shape;
    PoolGeom g = pool_geom(x, a.params);
    uint32_t local = row_local_size(d, uint64_t(x[0] * x[1] * g.oh));
    struct { uint32_t planes, h, w, oh, ow, sh, sw; int32_t ph, pw; } push{
        to_u32(x[0] * x[1], "planes"), uint32_t(x[2]), uint32_t(x[3]), uint32_t(g.oh), uint32_t(g.ow),
        uint32_t(g.sh), uint32_t(g.sw), int32_t(g.ph), int32_t(g.pw)};
    to_u32(numel(x), "max_pool2d input size");
    // The input as a texel buffer (a branch-free gather on CPU devices, see
    // PipelineDesc) unless it has more elements than the device allows in one.
    const bool texel = texels_allowed(a, {uint64_t(numel(x))});
    const rt::Pipeline& pipe = a.ctx.pipelines().get(rt::PipelineDesc{
        texel ? "max_pool2d" : "max_pool2d_ssbo", 3, sizeof(push),
        {local, uint32_t(g.kh), uint32_t(g.kw), uint32_t(g.sw), g.ow % 4 == 0}, texel ? 0x1u : 0u});
    a.seq.dispatch(pipe,
                   {{a.in[0].view, rt::Access::Read, texel ? VK_FORMAT_R32_SFLOAT : VK_FORMAT_UNDEFINED},
                    {a.out[0].view, rt::Access::Write}, {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), grid_groups(uint64_t(push.planes) * push.oh, local, d));
}

std::vector<TensorDesc> avg_infer(const std::vector<TensorDesc>& in, const Params&) {
    expect_input_count(in, 1, 1);
    expect_f32(in);
    const Shape& x = in[0].shape;
    if (x.size() != 4) throw Error("input must be [N, C, H, W], got " + shape_str(x));
    if (x[2] * x[3] == 0) throw Error("input " + shape_str(x) + " has empty planes");
    return {Shape{x[0], x[1], 1, 1}};
}

void avg_cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params&) {
    const Shape& x = in[0]->shape;
    const int64_t planes = x[0] * x[1], hw = x[2] * x[3];
    for (int64_t pl = 0; pl < planes; ++pl) {
        double s = 0;
        for (int64_t i = 0; i < hw; ++i) s += in[0]->data[size_t(pl * hw + i)];
        out[0]->data[size_t(pl)] = float(s / double(hw));
    }
}

void avg_gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const Shape& x = a.in[0].shape;
    uint32_t local = elementwise_local_size(d);
    const rt::Pipeline& pipe = pipeline(a.ctx, "global_avg_pool", 2, 8, {local});
    struct { uint32_t planes, hw; } push{to_u32(x[0] * x[1], "planes"), to_u32(x[2] * x[3], "plane size")};
    to_u32(numel(x), "global_avg_pool input size");
    a.seq.dispatch(pipe, {{a.in[0].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write}}, &push, sizeof(push),
                   grid_groups(push.planes, local, d));
}

}  // namespace

const OpDef op_max_pool2d{"max_pool2d", max_infer, max_cpu, max_gpu, 0,
                        {"kernel", "kernel_h", "kernel_w", "stride", "stride_h", "stride_w", "pad", "pad_h", "pad_w", "texel"}};
const OpDef op_global_avg_pool{"global_avg_pool", avg_infer, avg_cpu, avg_gpu, 0, {}};

}  // namespace vtloc::ops
