// The point encoder (PointNet++ MSG/SSG + group-all + MLP head) against the
// PyTorch goldens: fed the golden `point.cloud` (already normalised), every FPS
// and ball-query index must be equal, and F^p close. The goldens are the network
// in float64 rounded to float32; the engine runs fp32 GEMMs (fma, K up to 1027
// terms) through ~10 layers, so F^p differs from them by fp32 rounding only.
// Tolerances and the measured maxima are stated per config below.
#include <catch2/catch.hpp>

#include <cmath>

#include "base/error.h"
#include "bench/random_weights.h"
#include "engine/model/point_encoder.h"
#include "engine/model/prepared_weights.h"
#include "tests/golden.h"
#include "tests/run_both.h"

using namespace vtloc;

namespace {

struct Result {
    TensorMap out;
    double max_abs = 0, max_ref = 0;
};

// A golden config's weights, prepared as the model loads them.
WeightStore golden_weights(const std::string& dir, const std::string& name) {
    const WeightStore file = WeightStore::load(test::require_golden_file(dir, name + ".safetensors"));
    return prepare_weights(config_of(file), file);
}

// Builds the encoder on the golden cloud, runs it on the GPU (and the CPU
// reference when `cpu`), checks indices exactly and returns F^p's error.
Result run_golden(const std::string& dir, const std::string& name, bool fuse, bool cpu, test::Tolerance tol) {
    const WeightStore w = golden_weights(dir, name);
    test::Golden gold(test::require_golden_file(dir, name + ".golden.safetensors"));
    HostTensor cloud = gold.f32("point.cloud");
    Graph g;
    PointEncoderOutputs p = build_point_encoder(g, w, config_of(w), g.input("point.cloud", cloud.shape), {fuse});
    for (auto& [n, id] : p.indices) g.output(id, n);
    g.output(p.feature, "point.feature");
    TensorMap in{{"point.cloud", cloud}};
    Result r;
    r.out = cpu ? test::run_gpu_and_compare(g, w, in) : GpuExecutor(test::gpu(), g, w).run(in);
    test::require_no_validation_messages();
    CHECK(p.indices.size() >= 2);
    for (auto& [n, id] : p.indices) {
        INFO(name << " " << n);
        REQUIRE(gold.has(n));
        gold.compare_exact(n, r.out.at(n).ints());
    }
    HostTensor want = gold.f32("point.feature"), got = r.out.at("point.feature");
    REQUIRE(got.shape == Shape{1, want.size()});
    got.shape = want.shape;
    for (size_t i = 0; i < want.data.size(); ++i) {
        r.max_abs = std::max(r.max_abs, double(std::fabs(got.data[i] - want.data[i])));
        r.max_ref = std::max(r.max_ref, double(std::fabs(want.data[i])));
    }
    WARN(name << (fuse ? " fused" : " unfused") << ": max |F^p - golden| = " << r.max_abs << " (max |F^p| = " << r.max_ref << ")");
    gold.compare("point.feature", got, tol);
    return r;
}

}  // namespace

// Tiny configs: measured max |error| ~1e-6 against |F^p| ~1; the default
// 1e-4 + 1e-4*|ref| leaves two orders of magnitude of margin.
TEST_CASE("point encoder matches the PyTorch golden (vtloc-tiny: SSG, normals)", "[point][golden]") {
    run_golden(test::goldens_dir(), "vtloc-tiny", true, true, {});
    run_golden(test::goldens_dir(), "vtloc-tiny", false, true, {});
}

TEST_CASE("point encoder matches the PyTorch golden (vtloc-mcr-tiny: MSG, no normals)", "[point][golden]") {
    run_golden(test::goldens_dir(), "vtloc-mcr-tiny", true, true, {});
    run_golden(test::goldens_dir(), "vtloc-mcr-tiny", false, true, {});
}

// Paper config (1024 points, 512/128 centres, three scales, up to 128 neighbours,
// group-all 643 -> 1024): the GPU alone (the CPU reference would take most of
// the time budget; it is checked against the GPU on the tiny configs). fp32
// accumulation over K <= 1024 with values O(1): relative error ~1e-6 per layer.
TEST_CASE("point encoder matches the PyTorch golden (vtloc-r18, paper config)", "[point][golden][paper][long]") {
    run_golden(test::build_goldens_dir(), "vtloc-r18", true, false, {1e-4, 1e-4});
}

TEST_CASE("point encoder rejects bad clouds and configs", "[point]") {
    const WeightStore file = WeightStore::load(test::require_golden_file(test::goldens_dir(), "vtloc-tiny.safetensors"));
    const ModelConfig cfg = config_of(file);  // normals, sa1 samples 32 points
    const WeightStore w = prepare_weights(cfg, file);
    auto build_error = [&](Shape s) {
        Graph g;
        try {
            build_point_encoder(g, w, cfg, g.input("c", s));
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    CHECK_THAT(build_error({100, 3}), Catch::Contains("[N, 6] (xyz, normals)"));
    CHECK_THAT(build_error({100, 7}), Catch::Contains("[N, 6]"));
    CHECK_THAT(build_error({0, 6}), Catch::Contains("empty"));
    CHECK_THAT(build_error({31, 6}), Catch::Contains("samples 32 points but gets only 31"));
    CHECK(build_error({32, 6}) == "no error");

    HostTensor c = test::random_tensor({40, 6}, 3);
    CHECK_NOTHROW(check_object_cloud(c, cfg));
    c.data[6 * 7 + 1] = std::nanf("");
    CHECK_THROWS_WITH(check_object_cloud(c, cfg), Catch::Contains("NaN or infinite value at point 7"));
    c.data[6 * 7 + 1] = -INFINITY;
    CHECK_THROWS_WITH(check_object_cloud(c, cfg), Catch::Contains("NaN or infinite"));
    CHECK_THROWS_WITH(check_object_cloud(test::random_tensor({20, 6}, 3), cfg), Catch::Contains("fewer than the 32"));
    CHECK_THROWS_WITH(check_object_cloud(test::random_tensor({40, 3}, 3), cfg), Catch::Contains("[N, 6]"));
    CHECK_THROWS_WITH(check_object_cloud(HostTensor({0, 6}), cfg), Catch::Contains("empty"));

    nlohmann::json bad = w.config();
    bad["point"]["sa"][0]["radii"] = {0.3, 0.5};
    CHECK_THROWS_WITH(ModelConfig::parse(bad, "t"), Catch::Contains("one radius per nsample entry"));
    bad = w.config();
    bad["point"].erase("group_all_mlp");
    CHECK_THROWS_WITH(ModelConfig::parse(bad, "t"), Catch::Contains("'point.group_all_mlp' is missing"));
}

// PointEncoderOptions::point_major_rows changes where the rows between a scale's
// layers sit in memory, not the sums: F^p and every index equal the channel-major
// encoder's bit for bit.
static void point_major_equals_channel_major(const std::string& dir, const char* name) {
    INFO(name);
    const WeightStore w = golden_weights(dir, name);
    test::Golden gold(test::require_golden_file(dir, std::string(name) + ".golden.safetensors"));
    const HostTensor cloud = gold.f32("point.cloud");
    TensorMap out[2];
    for (bool pm : {false, true}) {
        PointEncoderOptions opt;
        opt.point_major_rows = pm;
        Graph g;
        g.output(build_point_encoder(g, w, config_of(w), g.input("point.cloud", cloud.shape), opt).feature, "f");
        int64_t readers = 0;  // the option must reach the layers
        for (const Node& n : g.nodes()) readers += n.params.get("x_point_major", 0) != 0;
        CHECK((readers > 0) == pm);
        out[pm] = GpuExecutor(test::gpu(), g, w).run({{"point.cloud", cloud}});
    }
    CHECK(out[0].at("f").data == out[1].at("f").data);
    test::require_no_validation_messages();
}

TEST_CASE("point encoder: point-major and channel-major rows give the same F^p bit for bit", "[point][golden]") {
    for (const char* name : {"vtloc-tiny", "vtloc-mcr-tiny"}) point_major_equals_channel_major(test::goldens_dir(), name);
}

// The paper config reaches the hidden-layer and padding paths; its pipelines are the
// long suite's (8 s cold here, beside the paper goldens it reads).
TEST_CASE("point encoder: point-major and channel-major rows give the same F^p bit for bit (vtloc-r18)",
          "[point][golden][paper][long]") {
    point_major_equals_channel_major(test::build_goldens_dir(), "vtloc-r18");
}

// A set abstraction whose MLP is one layer, on input wide enough for the per-point
// first layer (SA2 here: 128 + 3 channels, 32 points for 8 balls of 8): that layer is
// also the max, so it gathers its rows (the per-point path has no max). Fused equals
// unfused (point_group, linear, group_max) and the CPU reference.
TEST_CASE("point encoder: one-layer set-abstraction MLPs on wide inputs", "[point]") {
    nlohmann::json cfg = nlohmann::json::parse(bench::kR18Config);
    cfg["point"] = nlohmann::json::parse(R"({"n_points": 64, "use_normals": true,
        "sa": [{"npoint": 32, "radii": [0.5], "nsample": [8], "mlps": [[8, 128]]},
               {"npoint": 8, "radii": [0.7, 0.9], "nsample": [8, 16], "mlps": [[16], [24]]}],
        "group_all_mlp": [32], "mlp": [16]})");
    const WeightStore file = bench::random_point_weights(cfg, 5);
    const WeightStore w = prepare_weights(config_of(file), file);
    const TensorMap in{{"point.cloud", test::random_tensor({64, 6}, 6)}};
    HostTensor feature[2];
    for (bool fuse : {true, false}) {
        INFO((fuse ? "fused" : "unfused"));
        Graph g;
        PointEncoderOptions opt;
        opt.fuse = fuse;
        g.output(build_point_encoder(g, w, config_of(w), g.input("point.cloud", {64, 6}), opt).feature, "f");
        feature[fuse] = test::run_gpu_and_compare(g, w, in).at("f");
    }
    REQUIRE(feature[1].shape == (Shape{1, 128}));
    test::require_close(feature[1], feature[0], {}, "fused against unfused");
}
