// tactile_preprocess (SPEC section 2): GPU (validation on) against the CPU
// reference on real GelSight frames, on synthesised 480x640 and 240x320 frames
// and at odd shapes. The CPU reference works in double, the shader in fp32 over
// ~10 operations on values <= 2.7 in magnitude: 1e-5 abs + 1e-5 rel bounds it
// (measured worst case 7.2e-7, in the INFO). The PyTorch goldens are in
// test_tactile_encoder.cpp.
//
// GelSight frames: ObjectFolder 2.0 (R. Gao et al., "ObjectFolder 2.0: A Multisensory
// Object Dataset for Sim2Real Transfer", CVPR 2022), CC BY 4.0: the three shipped
// in examples/ (see examples/README.md), so a clone needs no ../shared beside it.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/ops/build.h"
#include "engine/ops/tactile_preprocess.h"
#include "engine/io/image.h"
#include "tests/harness.h"

using namespace vtloc;

namespace {

const test::Tolerance kPrepTol{1e-5, 1e-5};

// Both ways of reading the image (texel and storage buffers), outputs x.texel and x.storage.
Graph prep_graph(int64_t h, int64_t w, int64_t crop, int64_t size) {
    Graph g;
    int img = g.input("image", {h, w, 3}, ElemType::I32);
    for (ops::BufferPath path : ops::kBufferPaths)
        g.output(ops::tactile_preprocess(g, img, crop, size, "", path), std::string("x.") + ops::path_name(path));
    return g;
}

// Deterministic RGB frame: smooth shading, a dark dot grid (like the gel's
// markers) and per-pixel hash noise, so every tap of the resize matters.
std::vector<uint8_t> synthetic_frame(int64_t h, int64_t w) {
    std::vector<uint8_t> px(size_t(h * w * 3));
    for (int64_t y = 0; y < h; ++y)
        for (int64_t x = 0; x < w; ++x)
            for (int64_t c = 0; c < 3; ++c) {
                uint32_t hsh = uint32_t(y * 73856093 ^ x * 19349663 ^ c * 83492791) * 2654435761u;
                int v = int(60 + 90 * x / w + 60 * y / h + 25 * c) + int(hsh >> 28) - 8;
                if (y % 24 < 3 && x % 24 < 3) v /= 3;
                px[size_t((y * w + x) * 3 + c)] = uint8_t(std::clamp(v, 0, 255));
            }
    return px;
}

void check_frames(const std::vector<std::vector<uint8_t>>& frames, int64_t h, int64_t w, int64_t crop, int64_t size) {
    Graph g = prep_graph(h, w, crop, size);
    GpuExecutor exec(test::gpu(), g, WeightStore{});
    for (size_t i = 0; i < frames.size(); ++i) {
        TensorMap in{{"image", ops::tactile_image_tensor(frames[i].data(), h, w)}};
        TensorMap want = run_cpu(g, WeightStore{}, in);
        TensorMap got = exec.run(in);
        test::require_no_validation_messages();
        for (ops::BufferPath path : ops::kBufferPaths) {
            const std::string x = std::string("x.") + ops::path_name(path);
            double worst = 0;
            for (size_t k = 0; k < want.at(x).data.size(); ++k)
                worst = std::max(worst, double(std::abs(got.at(x).data[k] - want.at(x).data[k])));
            INFO("frame " << i << " " << h << "x" << w << " crop " << crop << " size " << size << ", " << x
                          << ": max |gpu - cpu| " << worst);
            test::require_close(got.at(x), want.at(x), kPrepTol, "preprocessed frame");
        }
    }
}

}  // namespace

TEST_CASE("centre crop offsets follow torchvision (round half to even, zero padding)", "[op][preprocess]") {
    CHECK(ops::center_crop_start(67, 64) == 2);  // 1.5 -> 2
    CHECK(ops::center_crop_start(69, 64) == 2);  // 2.5 -> 2
    CHECK(ops::center_crop_start(65, 64) == 0);  // 0.5 -> 0
    CHECK(ops::center_crop_start(71, 64) == 4);  // 3.5 -> 4
    CHECK(ops::center_crop_start(480, 320) == 80);
    CHECK(ops::center_crop_start(640, 320) == 160);
    CHECK(ops::center_crop_start(240, 320) == -40);
    CHECK(ops::center_crop_start(63, 64) == 0);   // pads (64 - 63) // 2 = 0 before
    CHECK(ops::center_crop_start(120, 128) == -4);
}

TEST_CASE("tactile_preprocess matches the CPU reference at odd shapes", "[op][preprocess][tactile_preprocess]") {
    struct Case { int64_t h, w, crop, size; };
    for (const Case& c : {Case{9, 8, 16, 5},      // padded on both axes, downscale
                          Case{37, 53, 32, 32},   // cropped on both axes, no resize
                          Case{50, 70, 50, 25},   // exact factor 2
                          Case{21, 13, 8, 17},    // upscale
                          Case{67, 69, 64, 41}}) {  // half-to-even offsets on both axes
        std::vector<uint8_t> px(size_t(c.h * c.w * 3));
        uint32_t s = 12345;
        for (auto& v : px) v = uint8_t((s = s * 1664525u + 1013904223u) >> 24);
        check_frames({px}, c.h, c.w, c.crop, c.size);
    }
}

TEST_CASE("tactile_preprocess on real GelSight frames and 480x640 / 240x320 frames", "[op][preprocess]") {
    std::vector<std::vector<uint8_t>> frames;
    for (const char* name : {"touch_01.png", "touch_02.png", "touch_03.png"}) {
        io::RgbImage im = io::load_tactile_image(VTLOC_SOURCE_DIR "/examples/" + std::string(name));
        REQUIRE((im.height == 120 && im.width == 160));
        frames.push_back(im.pixels);
    }
    check_frames(frames, 120, 160, 320, 224);  // paper config: crop larger than the frame
    check_frames(frames, 120, 160, 128, 40);   // tiny config
    check_frames({synthetic_frame(480, 640)}, 480, 640, 320, 224);
    check_frames({synthetic_frame(240, 320)}, 240, 320, 320, 224);
}

TEST_CASE("tactile_preprocess takes a batch of frames, each as if alone", "[op][preprocess]") {
    // [B, H, W, 3] -> [B, 3, S, S]: GPU against CPU, and each frame of the batch
    // bit-identical to the single-frame op's output on the GPU.
    const int64_t B = 3, h = 37, w = 53, crop = 40, size = 23;
    HostTensor batch({B, h, w, 3}, ElemType::I32);
    uint32_t s = 777;
    for (size_t i = 0; i < batch.data.size(); ++i) batch.set_int(i, int32_t((s = s * 1664525u + 1013904223u) >> 24));
    Graph g;
    g.output(ops::tactile_preprocess(g, g.input("image", batch.shape, ElemType::I32), crop, size), "x");
    TensorMap out = test::run_gpu_and_compare(g, WeightStore{}, {{"image", batch}}, kPrepTol);
    REQUIRE(out.at("x").shape == Shape{B, 3, size, size});
    GpuExecutor exec(test::gpu(), prep_graph(h, w, crop, size), WeightStore{});
    const size_t in_n = size_t(h * w * 3), out_n = size_t(3 * size * size);
    for (int64_t b = 0; b < B; ++b) {
        HostTensor one({h, w, 3}, ElemType::I32);
        std::copy(batch.data.begin() + std::ptrdiff_t(b * in_n), batch.data.begin() + std::ptrdiff_t((b + 1) * in_n), one.data.begin());
        TensorMap single = exec.run({{"image", one}});
        const auto& x = out.at("x").data;
        for (ops::BufferPath path : ops::kBufferPaths)
            CHECK(std::vector<float>(x.begin() + std::ptrdiff_t(b * out_n), x.begin() + std::ptrdiff_t((b + 1) * out_n)) ==
                  single.at(std::string("x.") + ops::path_name(path)).data);
    }
    test::require_no_validation_messages();
    Graph bad;
    REQUIRE_THROWS_WITH(ops::tactile_preprocess(bad, bad.input("e", {0, 9, 9, 3}, ElemType::I32), 8, 8),
                        Catch::Contains("is empty"));
}

TEST_CASE("tactile_preprocess rejects bad images and parameters", "[op][preprocess]") {
    Graph g;
    REQUIRE_THROWS_WITH(ops::tactile_preprocess(g, g.input("a", {7, 9, 3}, ElemType::I32), 8, 8),
                        Catch::Contains("smaller than 8x8"));
    REQUIRE_THROWS_WITH(ops::tactile_preprocess(g, g.input("b", {9, 9, 4}, ElemType::I32), 8, 8),
                        Catch::Contains("must be [H, W, 3] (RGB) or a batch"));
    REQUIRE_THROWS_WITH(ops::tactile_preprocess(g, g.input("c", {9, 9, 3}), 8, 8),
                        Catch::Contains("must be I32"));
    // Raw Params on purpose: a missing size must be refused at Graph::add.
    REQUIRE_THROWS_WITH(g.add1("tactile_preprocess", {g.input("d", {9, 9, 3}, ElemType::I32)}, {{"crop", 8}}),
                        Catch::Contains("param size"));
    // A 5x5 frame converts, and the graph built for it names the problem.
    std::vector<uint8_t> tiny(5 * 5 * 3, 7);
    HostTensor t = ops::tactile_image_tensor(tiny.data(), 5, 5);
    CHECK(t.shape == Shape{5, 5, 3});
    CHECK(t.int_at(74) == 7);
    REQUIRE_THROWS_WITH(prep_graph(5, 5, 8, 8), Catch::Contains("[5, 5, 3] is smaller than 8x8"));
}
