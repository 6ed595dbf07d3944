// Self-test cases: conv2d (texel and storage-buffer paths, both weight
// layouts, the tile shapes the device picks), max_pool2d, global_avg_pool and
// tactile_preprocess (the shapes of tests/test_conv.cpp and
// tests/test_tactile_preprocess.cpp).
#include <cmath>

#include "engine/check/op_selftest.h"
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
    bool texel;
    const char* why;
};

OpCase conv_case(const Conv& k, uint32_t seed) {
    const int64_t cin = k.x[1];
    const int64_t oh = (k.x[2] + 2 * k.ph - k.kh) / k.sh + 1, ow = (k.x[3] + 2 * k.pw - k.kw) / k.sw + 1;
    OpCase c("conv2d", std::string(k.why) + ": x" + shape_str(k.x) + " -> " + std::to_string(k.cout) + " k" +
                           std::to_string(k.kh) + "x" + std::to_string(k.kw) + " s" + std::to_string(k.sh) +
                           (k.layout == ops::kConvIHWO ? " IHWO" : " OIHW") +
                           (k.texel ? " texel" : " storage-buffer"));
    const float bound = 1.0f / std::sqrt(float(cin * k.kh * k.kw));
    HostTensor w = random_tensor({k.cout, cin, k.kh, k.kw}, seed + 1, -bound, bound);
    if (k.layout == ops::kConvIHWO) w = ops::conv_weight_to_ihwo(w);
    std::vector<int> in{c.input("x", random_tensor(k.x, seed, -2.0f, 2.0f)), c.weight("w", w)};
    if (k.bias) in.push_back(c.weight("b", random_tensor({k.cout}, seed + 2, -0.5f, 0.5f)));
    if (k.residual) in.push_back(c.input("res", random_tensor({k.x[0], k.cout, oh, ow}, seed + 3)));
    Params p{{"stride_h", double(k.sh)}, {"stride_w", double(k.sw)}, {"pad_h", double(k.ph)},
             {"pad_w", double(k.pw)}, {"act", double(k.act)}, {"slope", 0.1},
             {"residual", k.residual ? 1.0 : 0.0}, {"weight_layout", double(k.layout)},
             {"texel", k.texel ? 1.0 : 0.0}};
    c.output(c.g.add1("conv2d", in, p), "y");
    return c;
}

}  // namespace

std::vector<OpCase> image_cases(const rt::DeviceInfo&) {
    using ops::kConvIHWO, ops::kConvOIHW, ops::kActNone, ops::kActRelu, ops::kActLeaky;
    std::vector<OpCase> v;
    const Conv convs[] = {
        {{1, 3, 37, 53}, 10, 7, 7, 2, 2, 3, 3, true, false, kActRelu, kConvOIHW, true, "stem geometry, odd image"},
        {{2, 13, 17, 19}, 6, 1, 1, 2, 2, 0, 0, true, true, kActNone, kConvIHWO, true, "1x1 downsample, residual"},
        {{1, 6, 13, 10}, 12, 3, 3, 1, 1, 1, 1, true, true, kActRelu, kConvIHWO, true, "vec4 weights"},
        {{1, 9, 15, 14}, 20, 3, 3, 2, 2, 1, 1, false, false, kActNone, kConvIHWO, true, "partial channel block"},
        {{2, 4, 12, 23}, 5, 2, 5, 2, 1, 0, 2, false, false, kActLeaky, kConvOIHW, true, "rectangular kernel"},
        {{1, 7, 12, 16}, 8, 3, 3, 1, 1, 1, 1, true, true, kActRelu, kConvIHWO, true, "rows of 4n floats (x-shift)"},
        {{1, 3, 37, 53}, 10, 7, 7, 2, 2, 3, 3, true, false, kActRelu, kConvOIHW, false, "stem geometry"},
        {{1, 6, 13, 10}, 12, 3, 3, 1, 1, 1, 1, true, true, kActRelu, kConvIHWO, false, "vec4 weights"},
    };
    uint32_t seed = 1;
    for (const Conv& k : convs) v.push_back(conv_case(k, seed++));

    struct Pool { Shape x; Params p; const char* why; };
    for (const Pool& k : {Pool{{1, 5, 37, 53}, {{"kernel", 3}, {"stride", 2}, {"pad", 1}}, "3x3 s2 p1, texel"},
                          Pool{{1, 5, 37, 53}, {{"kernel", 3}, {"stride", 2}, {"pad", 1}, {"texel", 0}},
                               "3x3 s2 p1, storage-buffer"},
                          Pool{{1, 4, 11, 7}, {{"kernel_h", 3}, {"kernel_w", 2}, {"stride_h", 1}, {"stride_w", 2},
                                               {"pad_h", 1}}, "rectangular window"}}) {
        OpCase c("max_pool2d", std::string(k.why) + ": x" + shape_str(k.x));
        c.output(c.g.add1("max_pool2d", {c.input("x", random_tensor(k.x, 50, -3.0f, 3.0f))}, k.p), "y");
        c.tol = {0.0, 0.0};  // a max is exact
        v.push_back(std::move(c));
    }
    for (const Shape& s : {Shape{2, 33, 7, 7}, Shape{1, 3, 56, 57}}) {
        OpCase c("global_avg_pool", std::string("x").append(shape_str(s)));
        c.output(c.g.add1("global_avg_pool", {c.input("x", random_tensor(s, 60, -2.0f, 2.0f))}), "y");
        v.push_back(std::move(c));
    }

    struct Prep { int64_t h, w, crop, size; const char* why; };
    for (const Prep& k : {Prep{9, 8, 16, 5, "padded, downscale"}, Prep{37, 53, 32, 32, "cropped, no resize"},
                          Prep{21, 13, 8, 17, "upscale"}, Prep{67, 69, 64, 41, "half-to-even offsets"}}) {
        std::vector<uint8_t> px(size_t(k.h * k.w * 3));
        uint32_t s = 12345;
        for (auto& b : px) b = uint8_t((s = s * 1664525u + 1013904223u) >> 24);
        OpCase c("tactile_preprocess", std::string(k.why) + ": " + std::to_string(k.h) + "x" + std::to_string(k.w) +
                                           " crop " + std::to_string(k.crop) + " size " + std::to_string(k.size));
        int img = c.input("image", ops::tactile_image_tensor(px.data(), k.h, k.w));
        c.output(c.g.add1("tactile_preprocess", {img}, {{"crop", double(k.crop)}, {"size", double(k.size)}}), "x");
        c.tol = {1e-5, 1e-5};
        v.push_back(std::move(c));
    }
    return v;
}

}  // namespace vtloc::check
