// Bad input to the public API: each is one vtloc::api::Error, one line,
// naming the problem.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <limits>

#include "engine/safetensors.h"
#include "tests/api_test_util.h"
#include "tests/harness.h"

using namespace vtloc;
using Catch::Contains;

namespace {

api::PointCloud grid_cloud(int n) {
    api::PointCloud c;
    for (int i = 0; i < n; ++i) {
        c.xyz.insert(c.xyz.end(), {float(i % 7), float((i / 7) % 7), float(i / 49)});
        c.normals.insert(c.normals.end(), {0.f, 0.f, 1.f});
    }
    return c;
}

// The tensors of one weight file under the config of another.
std::string mismatched_weights(const std::string& tensors_from, const std::string& config_from, const std::string& out) {
    SafetensorsFile t = SafetensorsFile::load(tensors_from), c = SafetensorsFile::load(config_from);
    std::vector<TensorBlob> blobs;
    for (const TensorInfo& i : t.tensors()) {
        auto b = t.bytes(i);
        blobs.push_back({i.name, i.dtype, i.shape, std::vector<uint8_t>(b.begin(), b.end())});
    }
    write_safetensors(out, blobs, {{"vtloc.config", c.metadata().at("vtloc.config")}});
    return out;
}

}  // namespace

TEST_CASE("api: bad files are named", "[api][errors]") {
    api::Context ctx(test::validated());
    api::Model model(ctx, test::tiny_model());
    const std::string data = test::source_path("tests/cli/data/");
    CHECK_THAT(test::api_error([&] { api::load_tactile_image("no/such/touch.png"); }), Contains("no such file"));
    CHECK_THAT(test::api_error([&] { api::load_tactile_image(data); }), Contains("directory"));
    CHECK_THAT(test::api_error([&] { api::load_tactile_image(data + "nan.ply"); }), Contains("not an image"));
    CHECK_THAT(test::api_error([&] { api::load_tactile_image(data + "tiny_4x4.png"); }), Contains("8x8"));
    CHECK_THAT(test::api_error([&] { model.encode_object("no/such/mug.glb"); }), Contains("no such file"));
    CHECK_THAT(test::api_error([&] { model.encode_object(data + "points_only.gltf"); }), Contains("no triangles"));
    CHECK_THAT(test::api_error([&] { model.encode_object(data + "nan.ply"); }), Contains("point 1 has a non-finite"));
    CHECK_THAT(test::api_error([&] { model.encode_object(data + "inf.ply"); }), Contains("point 2 has a non-finite"));
    CHECK_THAT(test::api_error([&] { model.encode_object(data + "zero_normal.ply"); }), Contains("zero normal"));
    CHECK_THAT(test::api_error([&] { model.encode_object(data + "few_points.ply"); }),
               Contains("has 10 points, the model needs at least 32"));
    CHECK_THAT(test::api_error([&] { api::load_candidates("no/such.csv"); }), Contains("no such file"));
    test::require_no_validation(ctx);
}

TEST_CASE("api: bad weight files are named", "[api][errors]") {
    api::Context ctx(test::validated());
    const std::string text = test::temp_path("api_not_weights.safetensors");
    std::ofstream(text) << "not a weight file\n";
    CHECK_THAT(test::api_error([&] { api::Model(ctx, text); }), Contains("not a safetensors weight file"));
    CHECK_THAT(test::api_error([&] { api::Model(ctx, "no/such/model.safetensors"); }), Contains("no such file"));
    const std::string bare = test::temp_path("api_no_config.safetensors");
    write_safetensors(bare, {TensorBlob::f32("w", {2}, {1, 2})}, {});
    CHECK_THAT(test::api_error([&] { api::inspect_model(bare); }), Contains("vtloc.config"));
    const std::string other = mismatched_weights(test::tiny_model(),
                                                 test::source_path("weights_tools/goldens/vtloc-mcr-tiny.safetensors"),
                                                 test::temp_path("api_mismatched.safetensors"));
    std::string m = test::api_error([&] { api::Model(ctx, other); });
    CHECK_THAT(m, Contains("point.sa1.conv_blocks.0.0.weight"));
    CHECK_THAT(m, Contains("do not fit the file's config 'vtloc-mcr-tiny'"));
    // A config that breaks the schema is named by key.
    SafetensorsFile tiny = SafetensorsFile::load(test::tiny_model());
    std::string cfg = tiny.metadata().at("vtloc.config");
    cfg.replace(cfg.find("\"K\":5"), 5, "\"K\":0");
    const std::string badk = test::temp_path("api_bad_k.safetensors");
    write_safetensors(badk, {TensorBlob::f32("w", {1}, {1})}, {{"vtloc.config", cfg}});
    CHECK_THAT(test::api_error([&] { api::inspect_model(badk); }), Contains("'K' must be an integer"));
    test::require_no_validation(ctx);
}

TEST_CASE("api: bad arrays and options are named", "[api][errors]") {
    api::Context ctx(test::validated());
    api::Model model(ctx, test::tiny_model());
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    api::PointCloud c = grid_cloud(64);
    c.xyz[5 * 3 + 1] = nan;
    CHECK_THAT(test::api_error([&] { model.encode_object(c); }), Contains("point 5 has a non-finite"));
    c = grid_cloud(64);
    c.xyz[7 * 3] = inf;
    CHECK_THAT(test::api_error([&] { model.encode_object(c); }), Contains("point 7 has a non-finite"));
    c = grid_cloud(64);
    c.normals[9 * 3 + 2] = 0;
    CHECK_THAT(test::api_error([&] { model.encode_object(c); }), Contains("point 9 has a zero normal"));
    CHECK_THAT(test::api_error([&] { model.encode_object(grid_cloud(20)); }), Contains("needs at least 32"));
    c = grid_cloud(64);
    c.normals.pop_back();
    CHECK_THAT(test::api_error([&] { model.encode_object(c); }), Contains("normals"));
    CHECK_THAT(test::api_error([&] { model.encode_object(grid_cloud(64), {1, 2, nan}); }), Contains("NaN or inf"));

    api::Object obj = model.encode_object(grid_cloud(64), {0, 0, 0, 1, 1, 1, 2, 2, 2});
    api::TactileImage image{16, 16, std::vector<uint8_t>(16 * 16 * 3, 128)};
    CHECK_THAT(test::api_error([&] { model.localize(obj, image); }),
               Contains("K = 5 (the model's default) is larger than the candidate set (3 candidates)"));
    api::LocalizeOptions o;
    o.top_k = 3;
    CHECK_NOTHROW(model.localize(obj, image, o));
    o.top_k = 4;
    CHECK_THAT(test::api_error([&] { model.localize(obj, image, o); }), Contains("larger than the candidate set"));
    o.top_k = 2;
    o.iters = 65;
    CHECK_THAT(test::api_error([&] { model.localize(obj, image, o); }), Contains("0..64"));
    o.iters = 2;
    o.symmetry = api::Symmetry{{0, 0, 0}, {0, 0, 0}, 3};
    CHECK_THAT(test::api_error([&] { model.localize(obj, image, o); }), Contains("direction"));
    api::TactileImage small{4, 4, std::vector<uint8_t>(4 * 4 * 3, 128)};
    CHECK_THAT(test::api_error([&] { model.localize(obj, small, {.top_k = 2}); }), Contains("smallest accepted is 8x8"));
    api::TactileImage torn{16, 16, std::vector<uint8_t>(10)};
    CHECK_THAT(test::api_error([&] { model.localize(obj, torn, {.top_k = 2}); }), Contains("bytes"));

    api::Model cpu_only(test::tiny_model());
    CHECK_THAT(test::api_error([&] { cpu_only.encode_object(grid_cloud(64)); }), Contains("Backend::Cpu"));
    api::Model other(ctx, test::source_path("weights_tools/goldens/vtloc-mcr-tiny.safetensors"));
    CHECK_THAT(test::api_error([&] { other.localize(obj, image, {.top_k = 2}); }), Contains("another model"));
    CHECK_THAT(test::api_error([&] { model.localize(api::Object(), image); }), Contains("empty Object"));
    api::ContextOptions nodev = test::validated();
    nodev.device = "no-such-device-name";
    CHECK_THAT(test::api_error([&] { api::Context bad(nodev); }), Contains("no Vulkan compute device matches"));
    test::require_no_validation(ctx);
}
