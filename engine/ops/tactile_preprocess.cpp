// tactile_preprocess: I32 [H, W, 3] image (byte values, see tactile_preprocess.h)
// -> F32 [1, 3, size, size] network input (a batch [B, H, W, 3] -> [B, 3, size, size]), SPEC section 2: T / 255, centre crop
// (params crop; zero padding), bilinear resize to `size` (align_corners false,
// no antialias), ImageNet mean/std. Values outside 0..255 are clamped (both paths).
// Param texel (default 1; 0 = a storage buffer): how the shader reads the image.
// -> shaders/tactile_preprocess.comp (tactile_preprocess_ssbo.comp)
#include "engine/ops/tactile_preprocess.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {

HostTensor tactile_image_tensor(const uint8_t* rgb, int64_t height, int64_t width) {
    if (height < 0 || width < 0)
        throw Error("tactile image size " + std::to_string(height) + "x" + std::to_string(width) + " is negative");
    HostTensor t({height, width, 3}, ElemType::I32);
    for (size_t i = 0; i < t.data.size(); ++i) t.set_int(i, rgb[i]);
    return t;
}

int64_t center_crop_start(int64_t size, int64_t crop) {
    if (size < crop) return -((crop - size) / 2);
    const int64_t d = size - crop;  // start = d / 2, a half rounded to even
    return d % 2 == 0 ? d / 2 : (d / 2) % 2 == 0 ? d / 2 : d / 2 + 1;
}

namespace {

const double kMean[3] = {0.485, 0.456, 0.406};
const double kStd[3] = {0.229, 0.224, 0.225};

struct Prep {
    int64_t batch, h, w, crop, size;
};

Prep prep_params(const Shape& shape, const Params& p) {
    if ((shape.size() != 3 && shape.size() != 4) || shape.back() != 3)
        throw Error("image must be [H, W, 3] (RGB) or a batch [B, H, W, 3], got " + shape_str(shape));
    if (shape.size() == 4 && shape[0] < 1) throw Error("the image batch " + shape_str(shape) + " is empty");
    const int64_t batch = shape.size() == 4 ? shape[0] : 1;
    const Shape img(shape.end() - 3, shape.end());
    if (img[0] < kMinTactileSide || img[1] < kMinTactileSide)
        throw Error("image " + shape_str(img) + " is smaller than " + std::to_string(kMinTactileSide) + "x" +
                    std::to_string(kMinTactileSide));
    auto get = [&](const char* name) {
        double v = p.get(name, 0);
        if (v != std::floor(v) || v < 1 || v > 65536)
            throw Error(std::string("param ") + name + " must be an integer in 1..65536, got " + std::to_string(v));
        return int64_t(v);
    };
    Prep q{batch, img[0], img[1], get("crop"), get("size")};
    if (q.crop * (2 * q.size + 1) > (int64_t(1) << 31) - 1)
        throw Error("crop " + std::to_string(q.crop) + " and size " + std::to_string(q.size) +
                    " overflow the shader's 32-bit source index");
    return q;
}

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 1, 1);
    if (in[0].type != ElemType::I32) throw Error("image must be I32 (one byte value per element)");
    Prep q = prep_params(in[0].shape, p);
    return {Shape{q.batch, 3, q.size, q.size}};
}

// PyTorch's source index and the weight of the second tap, along one axis.
void source(int64_t o, int64_t in, int64_t out, int64_t& i0, int64_t& i1, double& l1) {
    if (in == out) { i0 = i1 = o; l1 = 0; return; }
    double s = std::max(double(in) / double(out) * (double(o) + 0.5) - 0.5, 0.0);
    i0 = std::min(int64_t(std::floor(s)), in - 1);
    i1 = i0 + (i0 < in - 1 ? 1 : 0);
    l1 = std::clamp(s - double(i0), 0.0, 1.0);
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const HostTensor& img = *in[0];
    Prep q = prep_params(img.shape, p);
    const int64_t top = center_crop_start(q.h, q.crop), left = center_crop_start(q.w, q.crop);
    auto px = [&](int64_t b, int64_t c, int64_t cy, int64_t cx) {  // crop space, [0, 1]
        int64_t y = cy + top, x = cx + left;
        if (y < 0 || y >= q.h || x < 0 || x >= q.w) return 0.0;
        return double(std::clamp(img.int_at(size_t(((b * q.h + y) * q.w + x) * 3 + c)), 0, 255)) / 255.0;
    };
    for (int64_t b = 0; b < q.batch; ++b)
        for (int64_t c = 0; c < 3; ++c)
            for (int64_t oy = 0; oy < q.size; ++oy)
                for (int64_t ox = 0; ox < q.size; ++ox) {
                    int64_t y0, y1, x0, x1;
                    double ly, lx;
                    source(oy, q.crop, q.size, y0, y1, ly);
                    source(ox, q.crop, q.size, x0, x1, lx);
                    double v = (1 - ly) * ((1 - lx) * px(b, c, y0, x0) + lx * px(b, c, y0, x1)) +
                               ly * ((1 - lx) * px(b, c, y1, x0) + lx * px(b, c, y1, x1));
                    out[0]->data[size_t(((b * 3 + c) * q.size + oy) * q.size + ox)] = float((v - kMean[c]) / kStd[c]);
                }
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    Prep q = prep_params(a.in[0].shape, a.params);
    // One invocation per 4 columns of an output row (all 3 channels): a workgroup per
    // row, its width the row's quads in whole subgroups.
    const uint32_t quads = uint32_t((q.size + 3) / 4), local = row_span_local_size(d, quads);
    const uint32_t gx = (quads + local - 1) / local;
    if (q.size > int64_t(d.max_workgroup_count[1]) || q.batch > int64_t(d.max_workgroup_count[2]))
        throw Error("a batch of " + std::to_string(q.batch) + " images of " + std::to_string(q.size) +
                    " rows needs more workgroups than the device allows");
    // The image as texels (a gather per fetch on CPU drivers, where a storage-buffer
    // load is a loop over the lanes) within the device's texel-buffer limit; param
    // texel = 0 forces the storage buffer (tests).
    const bool texel = texels_allowed(a, {uint64_t(numel(a.in[0].shape))});
    struct { uint32_t h, w, crop, s; int32_t top, left; } push{
        uint32_t(q.h), uint32_t(q.w), uint32_t(q.crop), uint32_t(q.size),
        int32_t(center_crop_start(q.h, q.crop)), int32_t(center_crop_start(q.w, q.crop))};
    const rt::Pipeline& pipe = a.ctx.pipelines().get(rt::PipelineDesc{
        texel ? "tactile_preprocess" : "tactile_preprocess_ssbo", 2, sizeof(push), {local, q.size % 4 == 0}, texel ? 0x1u : 0u});
    to_u32(numel(a.in[0].shape), "image size");
    to_u32(numel(a.out[0].shape), "output size");
    a.seq.dispatch(pipe, {{a.in[0].view, rt::Access::Read, texel ? VK_FORMAT_R32_SINT : VK_FORMAT_UNDEFINED},
                          {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), gx, uint32_t(q.size), uint32_t(q.batch));
}

}  // namespace

const OpDef op_tactile_preprocess{"tactile_preprocess", infer, cpu, gpu, 0, {"crop", "size", "texel"}};

}  // namespace vtloc::ops
