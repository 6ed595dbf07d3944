// Self-test cases: conv2d (texel and storage-buffer paths, both weight
// layouts, the tile shapes the device picks, big GPUs' split reduction),
// max_pool2d, global_avg_pool and tactile_preprocess (the shapes of tests/test_conv.cpp and
// tests/test_tactile_preprocess.cpp).
#include <cmath>

#include "engine/check/op_selftest.h"
#include "engine/ops/build.h"
#include "engine/ops/common.h"
#include "engine/ops/conv2d.h"
#include "engine/ops/tactile_preprocess.h"
#include "runtime/context.h"

namespace vtloc::check {

namespace {

struct Conv {
    Shape x;  // N, Cin, H, W
    int64_t cout, kh, kw, sh, sw, ph, pw;
    bool bias, residual;
    uint32_t act, layout;
    const char* why;
    int64_t split = 0;  // > 0: the input channels summed in that many parts (a big GPU's choice, forced)
    int64_t c_group = 0;  // > 0: accumulators a group in the fma chains (an AVX2 host's choice, forced)
};

OpCase conv_case(const Conv& k, ops::BufferPath path, uint32_t seed) {
    const int64_t cin = k.x[1];
    const int64_t oh = (k.x[2] + 2 * k.ph - k.kh) / k.sh + 1, ow = (k.x[3] + 2 * k.pw - k.kw) / k.sw + 1;
    OpCase c("conv2d", std::string(k.why) + ": x" + shape_str(k.x) + " -> " + std::to_string(k.cout) + " k" +
                           std::to_string(k.kh) + "x" + std::to_string(k.kw) + " s" + std::to_string(k.sh) +
                           (k.layout == ops::kConvIHWO ? " IHWO" : " OIHW") +
                           (k.split > 0 ? " in " + std::to_string(k.split) + " parts" : std::string()) +
                           (k.c_group > 0 ? " accumulators in " + std::to_string(k.c_group) + "s" : std::string()) +
                           " " + ops::path_name(path));
    const float bound = 1.0f / std::sqrt(float(cin * k.kh * k.kw));
    HostTensor w = random_tensor({k.cout, cin, k.kh, k.kw}, seed + 1, -bound, bound);
    if (k.layout == ops::kConvIHWO) w = ops::conv_weight_to_ihwo(w);
    const int x = c.input("x", random_tensor(k.x, seed, -2.0f, 2.0f)), wv = c.weight("w", w);
    const int b = k.bias ? c.weight("b", random_tensor({k.cout}, seed + 2, -0.5f, 0.5f)) : -1;
    const int res = k.residual ? c.input("res", random_tensor({k.x[0], k.cout, oh, ow}, seed + 3)) : -1;
    c.output(ops::conv2d(c.g, x, wv, b, res,
                         ops::Conv2d{k.sh, k.sw, k.ph, k.pw, k.layout, ops::Act(k.act), 0.1, path, k.split, k.c_group}),
             "y");
    return c;
}

}  // namespace

std::vector<OpCase> image_cases(const rt::DeviceInfo&) {
    using ops::kConvIHWO, ops::kConvOIHW, ops::kActNone, ops::kActRelu, ops::kActLeaky;
    std::vector<OpCase> v;
    const Conv convs[] = {
        {{1, 3, 37, 53}, 10, 7, 7, 2, 2, 3, 3, true, false, kActRelu, kConvOIHW, "stem geometry, odd image"},
        {{2, 13, 17, 19}, 6, 1, 1, 2, 2, 0, 0, true, true, kActNone, kConvIHWO, "1x1 downsample, residual"},
        {{1, 6, 13, 10}, 12, 3, 3, 1, 1, 1, 1, true, true, kActRelu, kConvIHWO, "vec4 weights"},
        {{1, 9, 15, 14}, 20, 3, 3, 2, 2, 1, 1, false, false, kActNone, kConvIHWO, "partial channel block"},
        {{2, 4, 12, 23}, 5, 2, 5, 2, 1, 0, 2, false, false, kActLeaky, kConvOIHW, "rectangular kernel"},
        {{1, 7, 12, 16}, 8, 3, 3, 1, 1, 1, 1, true, true, kActRelu, kConvIHWO, "rows of 4n floats (x-shift)"},
        // What big GPUs run for layer3/4 (ConvTiles::ksplit), forced here so that any device
        // checks the parts and their sum: an uneven last part, then bias, residual, activation.
        {{1, 19, 6, 5}, 12, 3, 3, 1, 1, 1, 1, true, true, kActRelu, kConvIHWO, "split reduction", 3},
        {{2, 16, 7, 4}, 8, 3, 3, 2, 2, 1, 1, false, false, kActLeaky, kConvOIHW, "split reduction, no epilogue", 2},
        // What an AVX2 host's lavapipe runs (ConvTiles::c_group), forced here for every device.
        {{1, 6, 14, 14}, 8, 3, 3, 1, 1, 1, 1, true, true, kActRelu, kConvIHWO, "accumulators in groups", 0, 4},
    };
    uint32_t seed = 1;
    for (const Conv& k : convs) {  // every case on every binding path
        for (ops::BufferPath path : ops::kBufferPaths) v.push_back(conv_case(k, path, seed));
        ++seed;
    }

    struct Pool { Shape x; ops::Pool2d p; const char* why; };
    for (const Pool& k : {Pool{{1, 5, 37, 53}, {3, 3, 2, 2, 1, 1}, "3x3 s2 p1"},
                          Pool{{1, 4, 11, 7}, {3, 2, 1, 2, 1, 0}, "rectangular window"},
                          Pool{{2, 3, 36, 40}, {3, 3, 2, 2, 1, 1}, "3x3 s2 p1, 4 outputs a step"}})
        for (ops::BufferPath path : ops::kBufferPaths) {
            OpCase c("max_pool2d", std::string(k.why) + ", " + ops::path_name(path) + ": x" + shape_str(k.x));
            ops::Pool2d p = k.p;
            p.path = path;
            c.output(ops::max_pool2d(c.g, c.input("x", random_tensor(k.x, 50, -3.0f, 3.0f)), p), "y");
            c.tol = {0.0, 0.0};  // a max is exact
            v.push_back(std::move(c));
        }
    for (const Shape& s : {Shape{2, 33, 7, 7}, Shape{1, 3, 56, 57}}) {
        OpCase c("global_avg_pool", std::string("x").append(shape_str(s)));
        c.output(ops::global_avg_pool(c.g, c.input("x", random_tensor(s, 60, -2.0f, 2.0f))), "y");
        v.push_back(std::move(c));
    }

    struct Prep { int64_t h, w, crop, size; const char* why; };
    for (const Prep& k : {Prep{9, 8, 16, 5, "padded, downscale"}, Prep{37, 53, 32, 32, "cropped, no resize"},
                          Prep{21, 13, 8, 17, "upscale"}, Prep{67, 69, 64, 41, "half-to-even offsets"}}) {
        std::vector<uint8_t> px(size_t(k.h * k.w * 3));
        uint32_t s = 12345;
        for (auto& b : px) b = uint8_t((s = s * 1664525u + 1013904223u) >> 24);
        for (ops::BufferPath path : ops::kBufferPaths) {
            OpCase c("tactile_preprocess", std::string(k.why) + ": " + std::to_string(k.h) + "x" + std::to_string(k.w) +
                                               " crop " + std::to_string(k.crop) + " size " + std::to_string(k.size) + " " +
                                               ops::path_name(path));
            int img = c.input("image", ops::tactile_image_tensor(px.data(), k.h, k.w));
            c.output(ops::tactile_preprocess(c.g, img, k.crop, k.size, "", path), "x");
            c.tol = {1e-5, 1e-5};
            v.push_back(std::move(c));
        }
    }
    {
        OpCase c("tactile_preprocess", "a batch of 3 frames 37x53, crop 40 size 23");
        HostTensor batch({3, 37, 53, 3}, ElemType::I32);
        uint32_t s = 777;
        for (size_t i = 0; i < batch.data.size(); ++i) batch.set_int(i, int32_t((s = s * 1664525u + 1013904223u) >> 24));
        c.output(ops::tactile_preprocess(c.g, c.input("image", batch), 40, 23), "x");
        c.tol = {1e-5, 1e-5};
        v.push_back(std::move(c));
    }
    return v;
}

}  // namespace vtloc::check
