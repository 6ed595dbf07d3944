// conv2d, max_pool2d and global_avg_pool: GPU (validation on) against the CPU
// references at odd shapes, with fixed seeds. Tolerance: the fp32 default
// 1e-4 + 1e-4*|ref|; the CPU conv accumulates in double over at most a few
// hundred terms of O(1) values, so this bounds the shader's fp32 rounding
// (measured max |gpu - cpu| 9.5e-7 on lavapipe; printed with -s).
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/ops/build.h"
#include "engine/ops/common.h"
#include "engine/ops/conv2d.h"
#include "tests/harness.h"

using namespace vtloc;
using vtloc::test::random_tensor;
using vtloc::test::run_gpu_and_compare;

namespace {

struct ConvCase {
    Shape x;              // N, Cin, H, W
    int64_t cout, kh, kw;
    int64_t sh, sw, ph, pw;
    bool bias, residual;
    uint32_t act;
    uint32_t layout;
    int64_t split = 0;  // > 0: the input channels summed in that many parts (a big GPU's choice, forced here)
    int64_t c_group = 0;  // > 0: accumulators a group in the fma chains (an AVX2 host's choice, forced here)
};

// Every case on every binding path (texel buffers and the storage-buffer fallback
// that runs when a tensor exceeds the device's maxTexelBufferElements).
// Returns each path's output.
std::vector<HostTensor> check_conv(const ConvCase& c, uint32_t seed) {
  std::vector<HostTensor> outs;
  for (ops::BufferPath path : ops::kBufferPaths) {
    const int64_t cin = c.x[1];
    const int64_t oh = (c.x[2] + 2 * c.ph - c.kh) / c.sh + 1, ow = (c.x[3] + 2 * c.pw - c.kw) / c.sw + 1;
    // PyTorch-like init bound keeps outputs O(1).
    float bound = 1.0f / std::sqrt(float(cin * c.kh * c.kw));
    HostTensor w = random_tensor({c.cout, cin, c.kh, c.kw}, seed + 1, -bound, bound);
    if (c.layout == ops::kConvIHWO) w = ops::conv_weight_to_ihwo(w);
    WeightStore ws;
    ws.add("w", w);
    ws.add("b", random_tensor({c.cout}, seed + 2, -0.5f, 0.5f));
    Graph g;
    const int x = g.input("x", c.x), wv = g.weight("w", w.shape), bv = c.bias ? g.weight("b", {c.cout}) : -1;
    TensorMap inputs{{"x", random_tensor(c.x, seed, -2.0f, 2.0f)}};
    const Shape rs{c.x[0], c.cout, oh, ow};
    const int res = c.residual ? g.input("res", rs) : -1;
    if (c.residual) inputs["res"] = random_tensor(rs, seed + 3);
    g.output(ops::conv2d(g, x, wv, bv, res, ops::Conv2d{c.sh, c.sw, c.ph, c.pw, c.layout, ops::Act(c.act), 0.1, path, c.split, c.c_group}),
             "y");
    INFO("conv x" << shape_str(c.x) << " -> " << c.cout << " k" << c.kh << "x" << c.kw << " s" << c.sh << "," << c.sw
                  << " p" << c.ph << "," << c.pw << " layout " << c.layout << " bias " << c.bias << " res "
                  << c.residual << " split " << c.split << " c_group " << c.c_group << " " << ops::path_name(path));
    TensorMap got = run_gpu_and_compare(g, ws, inputs);
    const TensorMap cpu_out = run_cpu(g, ws, inputs);
    const HostTensor& want = cpu_out.at("y");
    double worst = 0;
    for (size_t i = 0; i < want.data.size(); ++i)
        worst = std::max(worst, double(std::abs(got.at("y").data[i] - want.data[i])));
    INFO("max |gpu - cpu| " << worst);
    CHECK(worst < 1e-4);  // the default tolerance's absolute part; shown with -s
    outs.push_back(got.at("y"));
  }
  return outs;
}

}  // namespace

TEST_CASE("conv2d matches the CPU reference at odd shapes, on every binding path", "[op][conv2d]") {
    using ops::kConvIHWO, ops::kConvOIHW;
    // The ResNet stem's geometry on an odd image: 7x7, stride 2, pad 3.
    check_conv({{1, 3, 37, 53}, 10, 7, 7, 2, 2, 3, 3, true, false, ops::kActRelu, kConvOIHW}, 1);
    // 1x1 stride 2 (downsample), odd channels, residual, IHWO read one float at a time.
    check_conv({{2, 13, 17, 19}, 6, 1, 1, 2, 2, 0, 0, true, true, ops::kActNone, kConvIHWO}, 2);
    // 3x3 pad 1 with channel counts that no tile divides, both layouts.
    check_conv({{1, 5, 11, 9}, 7, 3, 3, 1, 1, 1, 1, true, true, ops::kActRelu, kConvOIHW}, 3);
    check_conv({{1, 6, 13, 10}, 12, 3, 3, 1, 1, 1, 1, true, true, ops::kActRelu, kConvIHWO}, 4);  // vec4 weights
    // 3x3 stride 2 pad 1 with a partial channel block on the vec4 path.
    check_conv({{1, 9, 15, 14}, 20, 3, 3, 2, 2, 1, 1, false, false, ops::kActNone, kConvIHWO}, 5);
    // Rectangular kernel, different strides and pads per axis, leaky ReLU, no bias.
    check_conv({{2, 4, 12, 23}, 5, 2, 5, 2, 1, 0, 2, false, false, ops::kActLeaky, kConvOIHW}, 6);
    // A single output pixel (kernel = padded input).
    check_conv({{1, 8, 3, 3}, 4, 5, 5, 1, 1, 1, 1, true, false, ops::kActTanh, kConvIHWO}, 7);
    // Fewer output channels than the smallest channel block (4).
    check_conv({{1, 5, 9, 8}, 3, 3, 3, 1, 1, 1, 1, true, true, ops::kActRelu, kConvOIHW}, 8);
    // Rows of a multiple of 4 floats, stride 1 and 2: every window row shares one
    // offset mod 4 (the shader's XSHIFT path; the shapes above take the per-row one).
    check_conv({{1, 7, 12, 16}, 8, 3, 3, 1, 1, 1, 1, true, true, ops::kActRelu, kConvIHWO}, 9);
    check_conv({{1, 4, 16, 16}, 8, 3, 3, 2, 2, 1, 1, true, false, ops::kActNone, kConvIHWO}, 10);
}

TEST_CASE("conv2d summing its input channels in parts matches the CPU reference", "[op][conv2d]") {
    using ops::kConvIHWO, ops::kConvOIHW;
    // Parts that do not divide the channels, one channel a part, more parts than
    // channels (clamped); bias, residual and activation in the second pass; both
    // binding paths, vec4 and scalar stores, batch 2.
    check_conv({{1, 37, 7, 7}, 12, 3, 3, 1, 1, 1, 1, true, true, ops::kActRelu, kConvIHWO, 5}, 21);
    check_conv({{2, 13, 9, 8}, 6, 3, 3, 2, 2, 1, 1, true, false, ops::kActLeaky, kConvOIHW, 3}, 22);
    check_conv({{1, 4, 8, 8}, 8, 1, 1, 1, 1, 0, 0, false, true, ops::kActNone, kConvIHWO, 4}, 23);
    check_conv({{1, 3, 6, 5}, 5, 3, 3, 1, 1, 1, 1, true, false, ops::kActTanh, kConvOIHW, 9}, 24);
    // The parts are really made: two dispatches, the second the sum.
    Graph g;
    const int x = g.input("x", {1, 16, 6, 6});
    g.output(ops::conv2d(g, x, g.weight("w", {8, 16, 3, 3}), -1, -1, ops::Conv2d{1, 1, 1, 1, kConvOIHW, ops::kActRelu, 0.1,
                                                                                   ops::BufferPath::Texel, 4}), "y");
    WeightStore ws;
    ws.add("w", random_tensor({8, 16, 3, 3}, 25));
    GpuExecutor ex(test::gpu(), g, ws);
    const auto& log = ex.sequence().dispatch_log();
    REQUIRE(log.size() == 2);
    CHECK(log[0].shader == "conv2d");
    CHECK(log[1].shader == "conv2d_split_sum");
    CHECK(ex.memory_plan().scratch_bytes == 4u * 8 * 6 * 6 * 4);
    test::require_no_validation_messages();
}

TEST_CASE("conv2d's accumulators in groups give the same bits as one at a time", "[op][conv2d]") {
    using ops::kConvIHWO, ops::kConvOIHW;
    // Each accumulator's fma chain keeps its order whatever the group, so every group size
    // must give the bits of 1. On lavapipe the first case's block rows are 7 columns wide
    // (groups of 4 and 3), the stem's 2 (one group, smaller than 4). Two cases only: each
    // group size is a pipeline of its own per path, ~0.3 s to compile cold.
    const ConvCase cases[] = {
        {{1, 6, 14, 14}, 8, 3, 3, 1, 1, 1, 1, true, true, ops::kActRelu, kConvIHWO},
        {{1, 3, 37, 53}, 10, 7, 7, 2, 2, 3, 3, true, false, ops::kActRelu, kConvOIHW},  // the stem: strided, KHB 1
    };
    uint32_t seed = 41;
    for (ConvCase c : cases) {
        c.c_group = 1;
        const std::vector<HostTensor> one = check_conv(c, seed);
        c.c_group = 4;
        const std::vector<HostTensor> grouped = check_conv(c, seed);
        REQUIRE(grouped.size() == one.size());
        for (size_t i = 0; i < one.size(); ++i) {
            INFO("path " << i);
            CHECK(grouped[i].data == one[i].data);
        }
        ++seed;
    }
}

TEST_CASE("conv2d tiles fit the device and its limits", "[op][conv2d]") {
    const rt::DeviceInfo& d = test::gpu().info();
    for (ops::ConvShape s : {ops::ConvShape{1, 3, 224, 224, 64, 7, 7, 2, 2, 112, 112},
                             ops::ConvShape{1, 512, 7, 7, 512, 3, 3, 1, 1, 7, 7},
                             ops::ConvShape{1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1}}) {
        ops::ConvTiles t = ops::choose_conv_tiles(d, s, true, true);
        CHECK(t.local <= d.max_invocations);
        CHECK(t.local <= d.max_workgroup_size[0]);
        CHECK(t.tm % 4 == 0);
        CHECK(t.r <= s.oh);
        CHECK(t.c <= s.ow);
        CHECK(t.accumulators() <= 392);  // the chooser's bound (compile time)
        CHECK((t.kh_block == s.kh || t.kh_block == 1));
    }
    // The shapes check_conv uses for the window-offset and vec4-store paths get
    // the ones they test (vec4 stores: OW and the block width multiples of 4) from
    // a CPU device's chooser, lavapipe's, on which CI runs them. A GPU's chooser
    // (run on an H200) takes other tiles for them: there they test whatever it takes.
    auto tiles = [&](ops::ConvShape s) { return ops::choose_conv_tiles(d, s, true, true); };
    if (d.type == VK_PHYSICAL_DEVICE_TYPE_CPU) {
        CHECK(tiles({1, 7, 12, 16, 8, 3, 3, 1, 1, 12, 16, 1}).x_shift == 3);
        CHECK(tiles({1, 7, 12, 16, 8, 3, 3, 1, 1, 12, 16, 1}).c % 4 == 0);
        CHECK(tiles({1, 4, 16, 16, 8, 3, 3, 2, 2, 8, 8, 1}).x_shift == 3);
        CHECK(tiles({1, 6, 13, 10, 12, 3, 3, 1, 1, 13, 10, 1}).x_shift == 4);
    }
    // A GPU-like device with small limits still gets a legal tile.
    rt::DeviceInfo small = d;
    small.type = VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU;
    small.max_invocations = 32;
    small.max_workgroup_size = {32, 32, 32};
    small.subgroup_size = 32;
    ops::ConvTiles t = ops::choose_conv_tiles(small, {1, 16, 9, 9, 16, 3, 3, 1, 1, 9, 9}, true, false);
    CHECK(t.local <= 32);
    CHECK(t.tm % 4 == 0);
    // lavapipe never splits; a GPU with many compute units splits a small output of a
    // long reduction (ResNet-18's layer4 at 224: 7x7x512 from 512 x 3x3) until the
    // dispatch offers fill_workgroups, and leaves a big output whole.
    const ops::ConvShape layer4{1, 512, 7, 7, 512, 3, 3, 1, 1, 7, 7, 1}, stem{1, 3, 224, 224, 64, 7, 7, 2, 2, 112, 112, 3};
    rt::DeviceInfo cpu = d;
    cpu.type = VK_PHYSICAL_DEVICE_TYPE_CPU;
    CHECK(ops::choose_conv_tiles(cpu, layer4, true, true).ksplit == 1);
    rt::DeviceInfo big = d;
    big.type = VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU;
    big.subgroup_size = 32;
    big.compute_units = 132;
    auto groups = [](const ops::ConvShape& s, const ops::ConvTiles& t) {
        auto up = [](int64_t a, int64_t b) { return (a + b - 1) / b; };
        return up(s.n * up(s.cout, t.tm) * up(s.oh, t.r) * up(s.ow, t.c), t.local) * t.ksplit;
    };
    const ops::ConvTiles t4 = ops::choose_conv_tiles(big, layer4, true, true);
    INFO("layer4 on 132 units: tm " << t4.tm << " r " << t4.r << " c " << t4.c << " local " << t4.local << " parts " << t4.ksplit);
    CHECK(t4.ksplit > 1);
    CHECK(uint64_t(groups(layer4, t4)) >= rt::fill_workgroups(big));
    CHECK(512 / t4.ksplit >= 8);  // at least 8 channels a part
    CHECK(ops::choose_conv_tiles(big, stem, true, true).ksplit == 1);
    big.compute_units = 8;  // a Jetson-class GPU: fewer parts
    CHECK(ops::choose_conv_tiles(big, layer4, true, true).ksplit < t4.ksplit);
    // Accumulators in groups of 4 only where lavapipe's JIT has 16 vector registers (AVX2),
    // on big convolutions; a GPU's compiler schedules its own.
    cpu.host_vector_registers = 16;
    CHECK(ops::choose_conv_tiles(cpu, layer4, true, true).c_group == 4);
    CHECK(ops::choose_conv_tiles(cpu, stem, true, true).c_group == 4);
    CHECK(ops::choose_conv_tiles(cpu, {1, 64, 56, 56, 128, 1, 1, 2, 2, 28, 28, 0}, true, true).c_group == 1);  // 6.4e6 MACs
    cpu.host_vector_registers = 32;
    CHECK(ops::choose_conv_tiles(cpu, layer4, true, true).c_group == 1);
    big.host_vector_registers = 0;
    CHECK(ops::choose_conv_tiles(big, layer4, true, true).c_group == 1);
}

TEST_CASE("conv2d names bad shapes and parameters", "[op][conv2d]") {
    Graph g;
    int x = g.input("x", {1, 3, 8, 8});
    REQUIRE_THROWS_WITH(ops::conv2d(g, x, g.weight("w4", {4, 2, 3, 3}), -1, -1, {}, "c1"),
                        Catch::Contains("c1") && Catch::Contains("3 channels") && Catch::Contains("expects 2"));
    int w = g.weight("w", {4, 3, 3, 3});
    // Raw Params on purpose: the shorthand "stride" with a bad value must be refused.
    REQUIRE_THROWS_WITH(g.add1("conv2d", {x, w}, {{"stride", 0}}), Catch::Contains("stride_h must be an integer >= 1"));
    REQUIRE_THROWS_WITH(g.add1("conv2d", {x, w}, {{"c_group", 9}}, "c9"), Catch::Contains("c9") && Catch::Contains("c_group must be an integer from 0 to 8, got 9"));
    REQUIRE_THROWS_WITH(ops::conv2d(g, x, g.weight("w9", {4, 3, 9, 9}), -1, -1, {}),
                        Catch::Contains("kernel 9x9 is larger than the padded input 8x8"));
    REQUIRE_THROWS_WITH(ops::conv2d(g, x, w, g.weight("b", {5}), -1, {}), Catch::Contains("bias [5]"));
    REQUIRE_THROWS_WITH(ops::conv2d(g, x, w, -1, g.input("r", {1, 4, 7, 7}), {}),
                        Catch::Contains("residual [1, 4, 7, 7] does not match the output [1, 4, 6, 6]"));
}

TEST_CASE("max_pool2d matches the CPU reference at odd shapes", "[op][pool][max_pool2d]") {
    struct Case { Shape x; ops::Pool2d p; };
    for (const Case& c : {Case{{1, 5, 37, 53}, {3, 3, 2, 2, 1, 1}}, Case{{2, 3, 8, 9}, {2, 2, 2, 2, 0, 0}},
                          Case{{1, 4, 11, 7}, {3, 2, 1, 2, 1, 0}},
                          Case{{2, 3, 36, 40}, {3, 3, 2, 2, 1, 1}},   // OW = 20: 4 outputs a step (ResNet's pool)
                          Case{{1, 2, 9, 12}, {3, 3, 1, 1, 1, 1}},    // the same at stride 1
                          Case{{1, 2, 10, 17}, {2, 3, 2, 3, 0, 1}}})  // OW = 6: not a multiple of 4
        for (ops::BufferPath path : ops::kBufferPaths) {
            Graph g;
            ops::Pool2d p = c.p;
            p.path = path;
            g.output(ops::max_pool2d(g, g.input("x", c.x), p), "y");
            INFO("max_pool2d " << shape_str(c.x) << " " << ops::path_name(path));
            run_gpu_and_compare(g, WeightStore{}, {{"x", random_tensor(c.x, 50, -3.0f, 3.0f)}}, {0.0, 0.0});
        }
    Graph g;
    int x = g.input("x", {1, 1, 4, 4});
    // Raw Params on purpose: bad or missing values must be refused at Graph::add.
    REQUIRE_THROWS_WITH(g.add1("max_pool2d", {x}, {{"kernel", 3}, {"pad", 2}}), Catch::Contains("at most half"));
    REQUIRE_THROWS_WITH(g.add1("max_pool2d", {x}), Catch::Contains("needs a kernel size"));
}

TEST_CASE("global_avg_pool matches the CPU reference", "[op][pool][global_avg_pool]") {
    for (const Shape& s : {Shape{1, 7, 5, 3}, Shape{2, 33, 7, 7}, Shape{1, 3, 56, 57}}) {
        Graph g;
        g.output(ops::global_avg_pool(g, g.input("x", s)), "y");
        INFO("global_avg_pool " << shape_str(s));
        run_gpu_and_compare(g, WeightStore{}, {{"x", random_tensor(s, 60, -2.0f, 2.0f)}}, {1e-6, 1e-5});
    }
}
