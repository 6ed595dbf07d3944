// Numeric edge cases through the public API: each gives a defined, finite result
// or one api::Error line naming the problem; never a silent NaN in an output.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <cstring>
#include <limits>

#include "engine/safetensors.h"
#include "tests/api_test_util.h"

using namespace vtloc;
using Catch::Contains;

namespace {

// A sphere of n points (radius r around c), normals outward.
api::PointCloud sphere(int n, double r, double c = 0) {
    api::PointCloud s;
    const double golden = std::acos(-1.0) * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
        const double z = 1 - 2 * (i + 0.5) / n, rho = std::sqrt(1 - z * z), th = golden * i;
        const double v[3] = {rho * std::cos(th), rho * std::sin(th), z};
        for (int k = 0; k < 3; ++k) {
            s.xyz.push_back(float(c + r * v[k]));
            s.normals.push_back(float(v[k]));
        }
    }
    return s;
}

api::TactileImage constant_image(uint8_t v, int h = 120, int w = 160) {
    return api::TactileImage{h, w, std::vector<uint8_t>(size_t(h * w * 3), v)};
}

void require_finite(const api::TouchResult& r) {
    for (double v : r.contact) REQUIRE(std::isfinite(v));
    for (float v : r.heatmap) REQUIRE(std::isfinite(v));
    for (float v : r.topk_score) REQUIRE(std::isfinite(v));
    if (r.alignment) REQUIRE(std::isfinite(*r.alignment));
}

}  // namespace

TEST_CASE("api: degenerate clouds are refused by name", "[api][errors][edge]") {
    api::Context ctx(test::validated());
    api::Model model(ctx, test::tiny_model());
    api::PointCloud same = sphere(64, 1.0);
    for (size_t i = 0; i < same.xyz.size(); ++i) same.xyz[i] = 3.0f;  // every point identical
    CHECK_THAT(test::api_error([&] { model.encode_object(same); }), Contains("identical"));
    api::PointCloud few = sphere(8, 1.0);  // fewer than the first stage samples
    CHECK_THAT(test::api_error([&] { model.encode_object(few); }), Contains("needs at least"));
    api::PointCloud zero_n = sphere(64, 1.0);
    zero_n.normals[9] = zero_n.normals[10] = zero_n.normals[11] = 0;
    CHECK_THAT(test::api_error([&] { model.encode_object(zero_n); }), Contains("zero normal"));
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        api::PointCloud c = sphere(64, 1.0);
        c.xyz[40] = bad;
        CHECK_THAT(test::api_error([&] { model.encode_object(c); }), Contains("point 13"));
        c = sphere(64, 1.0);
        c.normals[7] = bad;
        CHECK_THAT(test::api_error([&] { model.encode_object(c); }), Contains("point 2"));
        CHECK_THAT(test::api_error([&] { model.encode_object(sphere(64, 1.0), {0, 0, bad}); }), Contains("candidate 0"));
    }
    test::require_no_validation(ctx);
}

TEST_CASE("api: huge, tiny and repeated points give finite results", "[api][edge]") {
    api::Context ctx(test::validated());
    api::Model model(ctx, test::tiny_model());
    const api::TactileImage image = constant_image(128);
    for (double scale : {1e6, 1e-6, 1.0}) {
        INFO("radius " << scale);
        api::Object o = model.encode_object(sphere(200, scale, 5 * scale));
        const api::TouchResult r = model.localize(o, image);
        require_finite(r);
        // The contact comes back in object units, near the object.
        for (int k = 0; k < 3; ++k) CHECK(std::abs(r.contact[size_t(k)] - 5 * scale) <= 3 * scale);
    }
    // One point repeated many times next to a few distinct ones: FPS and ball query still pick valid indices.
    api::PointCloud rep = sphere(40, 1.0);
    for (int i = 0; i < 200; ++i) {
        rep.xyz.insert(rep.xyz.end(), {0.5f, 0.5f, 0.5f});
        rep.normals.insert(rep.normals.end(), {0.f, 0.f, 1.f});
    }
    require_finite(model.localize(model.encode_object(rep), image));
    test::require_no_validation(ctx);
}

TEST_CASE("api: black, saturated and constant images give finite results", "[api][edge]") {
    api::Context ctx(test::validated());
    api::Model model(ctx, test::tiny_model());
    api::Object o = model.encode_object(sphere(200, 30.0));
    for (uint8_t v : {uint8_t(0), uint8_t(255), uint8_t(77)}) {
        INFO("constant image " << int(v));
        require_finite(model.localize(o, constant_image(v)));
    }
    test::require_no_validation(ctx);
}

TEST_CASE("api: a weight file holding NaN or inf is refused at load", "[api][errors][edge]") {
    namespace fs = std::filesystem;
    SafetensorsFile f = SafetensorsFile::load(test::tiny_model());
    const fs::path out = fs::temp_directory_path() / "vtloc-test-nan-weights.safetensors";
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::infinity()}) {
        std::vector<TensorBlob> blobs;
        for (const TensorInfo& i : f.tensors()) {
            auto b = f.bytes(i);
            blobs.push_back({i.name, i.dtype, i.shape, std::vector<uint8_t>(b.begin(), b.end())});
            if (i.name == "ilu.convz.weight") {
                REQUIRE(i.dtype == DType::F32);
                std::memcpy(blobs.back().bytes.data() + 4 * 5, &bad, 4);
            }
        }
        write_safetensors(out.string(), blobs, f.metadata());
        api::Context ctx(test::validated());
        CHECK_THAT(test::api_error([&] { api::Model m(ctx, out.string()); }),
                   Contains("ilu.convz.weight") && Contains("NaN or inf") && Contains("element 5"));
    }
    fs::remove(out);
}
