// The whole model end to end (SPEC sections 2-3): a tactile image and an object
// cloud in, every SPEC section 8 tensor out, against the PyTorch goldens; and the
// cached-object, batched, run-time-N and CPU-reference paths against one-shot.
//
// Tolerance for features: goldens are float64 rounded to float32 while the engine
// runs float32 end to end (~20 convolutions, PointNet++ MLPs, GRU iterations), so
// errors of a few 1e-4 relative accumulate; 2e-3 + 2e-3*|ref| leaves margin.
// Indices (FPS, ball query, top-K) must match exactly.
#include <catch2/catch.hpp>
#include <cmath>

#include "base/error.h"
#include "engine/model/vtloc_runner.h"
#include "engine/ops/tactile_preprocess.h"
#include "tests/golden.h"

using namespace vtloc;

namespace {

constexpr test::Tolerance kFeature{2e-3, 2e-3};

struct GoldenCase {
    std::unique_ptr<test::Golden> golden;
    WeightStore weights;
    HostTensor image, cloud, candidates;
};

GoldenCase load_case(const std::string& dir, const std::string& name) {
    GoldenCase c;
    c.golden = std::make_unique<test::Golden>(test::require_golden_file(dir, name + ".golden.safetensors"));
    c.weights = WeightStore::load(test::require_golden_file(dir, name + ".safetensors"));
    const TensorInfo& ti = c.golden->file().at("input.tactile");
    c.image = ops::tactile_image_tensor(c.golden->file().bytes(ti).data(), ti.shape[0], ti.shape[1]);
    c.cloud = c.golden->f32("input.cloud");
    c.candidates = c.golden->f32("input.candidates");
    return c;
}

void compare_with_golden(const test::Golden& gold, const TouchResult& r) {
    for (const char* name : {"tactile.input", "tactile.feature", "point.feature", "gma.cloud", "gma.chamfer", "ilu.c",
                             "contact", "topk.score", "heatmap"}) {
        if (!gold.has(name)) continue;
        INFO("tensor " << name);
        REQUIRE(r.tensors.count(name));
        HostTensor got = r.tensors.at(name);
        got.shape = gold.shape(name);  // the engine keeps a batch axis of 1 on some
        gold.compare(name, got, kFeature);
    }
    gold.compare_exact("topk.index", r.tensors.at("topk.index").ints());
    for (const TensorInfo& t : gold.file().tensors())
        if (t.name.rfind("point.sa", 0) == 0) {
            INFO("tensor " << t.name);
            REQUIRE(r.tensors.count(t.name));
            gold.compare_exact(t.name, r.tensors.at(t.name).ints());
        }
    // Object units: the golden's contact.object came from its own c^p.
    HostTensor obj = gold.f32("contact.object");
    for (int i = 0; i < 3; ++i) CHECK(std::abs(r.contact[size_t(i)] - obj.data[size_t(i)]) <= 2e-3 * (1 + std::abs(obj.data[size_t(i)])));
}

void check_same(const TouchResult& a, const TouchResult& b, const std::string& what) {
    INFO(what);
    for (auto& [name, t] : b.tensors) {
        if (name.rfind("point.", 0) == 0) continue;  // object tensors exist on one path only
        REQUIRE(a.tensors.count(name));
        CHECK(a.tensors.at(name).shape == t.shape);
        if (t.type == ElemType::I32) CHECK(a.tensors.at(name).ints() == t.ints());
        else test::require_close(a.tensors.at(name), t, {1e-6, 1e-6}, what + ": " + name);
    }
}

}  // namespace

// One touch through the one-shot path, every tensor against the golden.
TouchResult check_end_to_end(const std::string& dir, const std::string& name) {
    GoldenCase c = load_case(dir, name);
    VtlocRunner runner(c.weights, &test::gpu());
    TouchResult r = runner.localize_once(c.image, c.cloud, &c.candidates);
    test::require_no_validation_messages();
    compare_with_golden(*c.golden, r);
    return r;
}

TEST_CASE("vtloc-tiny end to end matches the PyTorch golden", "[model][golden]") {
    CHECK(check_end_to_end(test::goldens_dir(), "vtloc-tiny").alignment.has_value());
}

TEST_CASE("vtloc-mcr-tiny end to end matches the PyTorch golden", "[model][golden]") {
    CHECK_FALSE(check_end_to_end(test::goldens_dir(), "vtloc-mcr-tiny").alignment.has_value());
}

TEST_CASE("vtloc-r18 (the paper's config) end to end matches the PyTorch golden", "[model][golden][paper][long]") {
    CHECK(check_end_to_end(test::build_goldens_dir(), "vtloc-r18").alignment.has_value());
}

TEST_CASE("vtloc-mcr (paper-size MCR baseline) end to end matches the PyTorch golden", "[model][golden][paper][long]") {
    CHECK_FALSE(check_end_to_end(test::build_goldens_dir(), "vtloc-mcr").alignment.has_value());
}

TEST_CASE("cached object and batched touches equal the one-shot path", "[model]") {
    for (const char* name : {"vtloc-tiny", "vtloc-mcr-tiny"}) {
        INFO(name);
        GoldenCase c = load_case(test::goldens_dir(), name);
        VtlocRunner runner(c.weights, &test::gpu());
        // Three touches: the golden frame, its mirror and a darker copy.
        std::vector<HostTensor> images{c.image, c.image, c.image};
        const int64_t H = c.image.shape[0], W = c.image.shape[1];
        for (int64_t y = 0; y < H; ++y)
            for (int64_t x = 0; x < W; ++x)
                for (int ch = 0; ch < 3; ++ch) {
                    size_t i = size_t((y * W + x) * 3 + ch);
                    images[1].set_int(i, c.image.int_at(size_t((y * W + (W - 1 - x)) * 3 + ch)));
                    images[2].set_int(i, c.image.int_at(i) / 2);
                }
        EncodedObject obj = runner.encode_object(c.cloud, &c.candidates);
        c.golden->compare("point.feature", HostTensor({obj.feature.size()}, obj.feature.data), kFeature);
        std::vector<TouchResult> batch = runner.localize(obj, images);
        REQUIRE(batch.size() == 3);
        const size_t nodes3 = runner.last_graph()->nodes().size();
        for (size_t b = 0; b < images.size(); ++b) {
            TouchResult once = runner.localize_once(images[b], c.cloud, &c.candidates);
            check_same(batch[b], once, "batch touch " + std::to_string(b) + " vs one-shot");
            TouchResult single = runner.localize(obj, {images[b]}).at(0);
            check_same(single, once, "cached touch " + std::to_string(b) + " vs one-shot");
        }
        // A batch is one network: 16 touches take the nodes that 3 take.
        std::vector<HostTensor> sixteen(16, images[1]);
        std::vector<TouchResult> many = runner.localize(obj, sixteen);
        CHECK(runner.last_graph()->nodes().size() == nodes3);
        check_same(many[15], batch[1], "touch 15 of 16 vs touch 1 of 3");
        test::require_no_validation_messages();
    }
}

TEST_CASE("ILU iterations are chosen per run without rebuilding", "[model]") {
    GoldenCase c = load_case(test::goldens_dir(), "vtloc-tiny");
    VtlocRunner runner(c.weights, &test::gpu());
    EncodedObject obj = runner.encode_object(c.cloud, &c.candidates);
    TouchOptions o;
    o.iters = 0;
    TouchResult r0 = runner.localize(obj, {c.image}, o).at(0);
    CHECK(r0.tensors.at("ilu.c").shape == Shape{0, 3});
    for (int i = 0; i < 3; ++i) CHECK(r0.contact_normalised[size_t(i)] == 0.0);  // SPEC: N = 0 gives c^p = 0
    o.iters = 4;
    TouchResult r4 = runner.localize(obj, {c.image}, o).at(0);
    o.iters = 2;
    TouchResult r2 = runner.localize(obj, {c.image}, o).at(0);
    REQUIRE(r2.tensors.at("ilu.c").shape == Shape{2, 3});
    for (size_t i = 0; i < 6; ++i) CHECK(r2.tensors.at("ilu.c").data[i] == r4.tensors.at("ilu.c").data[i]);
    o.iters = 64;
    CHECK(runner.localize(obj, {c.image}, o).at(0).tensors.at("ilu.c").shape == Shape{64, 3});
    o.iters = 65;
    REQUIRE_THROWS_WITH(runner.localize(obj, {c.image}, o), Catch::Contains("0..64"));
    test::require_no_validation_messages();
}

TEST_CASE("the GPU and the CPU reference backends agree on the whole model", "[model]") {
    GoldenCase c = load_case(test::goldens_dir(), "vtloc-tiny");
    VtlocRunner gpu(c.weights, &test::gpu()), cpu(c.weights, nullptr);
    TouchOptions o;
    o.symmetry = Symmetry{{0, 0, 0}, {0, 0, 1}, 3};
    TouchResult g = gpu.localize_once(c.image, c.cloud, &c.candidates, o);
    TouchResult h = cpu.localize_once(c.image, c.cloud, &c.candidates, o);
    for (auto& [name, t] : h.tensors) {
        INFO(name);
        if (t.type == ElemType::I32) CHECK(g.tensors.at(name).ints() == t.ints());
        else test::require_close(g.tensors.at(name), t, kFeature, name);
    }
    test::require_no_validation_messages();
}

TEST_CASE("the tiny model gives the same bits in every schedule", "[model]") {
    GoldenCase c = load_case(test::goldens_dir(), "vtloc-tiny");
    VtlocRunner runner(c.weights, &test::gpu());
    runner.set_schedule(Schedule::Serial);
    const TouchResult ref = runner.localize_once(c.image, c.cloud, &c.candidates);
    const uint32_t serial_barriers = runner.last_barriers();
    for (Schedule s : {Schedule::Steps, Schedule::Late}) {
        INFO(schedule_name(s));
        runner.set_schedule(s);
        const TouchResult got = runner.localize_once(c.image, c.cloud, &c.candidates);
        CHECK(runner.last_barriers() < serial_barriers);
        for (auto& [name, t] : ref.tensors) {
            INFO(name);
            REQUIRE(got.tensors.count(name));
            CHECK(got.tensors.at(name).data == t.data);
        }
    }
    test::require_no_validation_messages();
}

TEST_CASE("bad inputs to the model are named", "[model]") {
    GoldenCase c = load_case(test::goldens_dir(), "vtloc-tiny");
    VtlocRunner runner(c.weights, &test::gpu());
    HostTensor nan_cloud = c.cloud;
    nan_cloud.data[7 * 6 + 1] = std::nanf("");
    REQUIRE_THROWS_WITH(runner.encode_object(nan_cloud), Catch::Contains("NaN"));
    HostTensor few({4, 6});
    REQUIRE_THROWS_WITH(runner.encode_object(few), Catch::Contains("needs at least"));
    HostTensor empty({0, 6});
    REQUIRE_THROWS(runner.encode_object(empty));
    HostTensor two_cands({2, 3}, {0, 0, 0, 1, 1, 1});
    REQUIRE_THROWS_WITH(runner.localize_once(c.image, c.cloud, &two_cands), Catch::Contains("exceeds the 2 candidates"));
    HostTensor tiny_image = ops::tactile_image_tensor(std::vector<uint8_t>(4 * 4 * 3, 9).data(), 4, 4);
    REQUIRE_THROWS_WITH(runner.localize_once(tiny_image, c.cloud, nullptr), Catch::Contains("8"));
    REQUIRE_THROWS_WITH(runner.localize(EncodedObject{}, {c.image}), Catch::Contains("not encoded"));
    test::require_no_validation_messages();
}

TEST_CASE("a model's weights are resident once for all its graph shapes", "[model]") {
    GoldenCase c = load_case(test::goldens_dir(), "vtloc-tiny");
    VtlocRunner runner(c.weights, &test::gpu());
    const TouchResult once = runner.localize_once(c.image, c.cloud, &c.candidates);  // reads every weight
    const VtlocRunner::MemoryUse m1 = runner.last_memory();
    REQUIRE(m1.resident_weight_bytes > 0);
    CHECK(m1.weight_bytes <= m1.resident_weight_bytes);
    CHECK(m1.resident_weight_bytes - m1.weight_bytes < 1024);  // the buffers' alignment padding

    // Three more shapes: the object branch alone, a batch of 2, another K.
    EncodedObject obj = runner.encode_object(c.cloud, &c.candidates);
    CHECK(runner.last_memory().weight_bytes < m1.resident_weight_bytes);
    runner.localize(obj, {c.image, c.image});
    TouchOptions k3;
    k3.k = 3;
    const TouchResult r = runner.localize(obj, {c.image}, k3).at(0);
    CHECK(runner.last_memory().resident_weight_bytes == m1.resident_weight_bytes);  // nothing uploaded again

    // The shared weights give what a runner of that one shape gives.
    VtlocRunner fresh(c.weights, &test::gpu());
    const TouchResult f = fresh.localize(fresh.encode_object(c.cloud, &c.candidates), {c.image}, k3).at(0);
    check_same(r, f, "K = 3 after other shapes vs a fresh runner");
    check_same(runner.localize(obj, {c.image}).at(0), once, "cached touch vs one-shot");
    test::require_no_validation_messages();
}
