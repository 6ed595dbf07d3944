// Clouds robots have, through the public API: a depth camera's view (depth
// PNG + intrinsics + mask -> partial cloud, normals towards the camera), a
// large cloud reduced to the model's point count (voxel grid, then FPS), and
// their errors. Depth images are written here with OpenCV.
#include <catch2/catch.hpp>

#include <cmath>
#include <opencv2/core.hpp>
#include <random>

#include "engine/io/depth.h"
#include "engine/io/image_mat.h"
#include "engine/model/cloud_reduce.h"
#include "tests/api_test_util.h"
#include "tests/harness.h"

using namespace vtloc;

namespace {

constexpr double kFx = 300, kFy = 310, kCx = 79.5, kCy = 59.5;

// A 160 x 120 depth image of a sphere (radius 40 mm, centre 400 mm ahead) on
// no background; the mask keeps the left half of the image.
void write_sphere_depth(const std::string& depth, const std::string& mask) {
    cv::Mat d(120, 160, CV_16UC1, cv::Scalar(0)), m(120, 160, CV_8UC1, cv::Scalar(0));
    for (int v = 0; v < 120; ++v)
        for (int u = 0; u < 160; ++u) {
            const double rx = (u - kCx) / kFx, ry = (v - kCy) / kFy;  // ray (rx, ry, 1)
            const double a = rx * rx + ry * ry + 1, b = -2 * 400, c = 400.0 * 400 - 40.0 * 40;
            const double disc = b * b - 4 * a * c;
            if (disc < 0) continue;
            d.at<uint16_t>(v, u) = uint16_t(std::lround((-b - std::sqrt(disc)) / (2 * a)));
            m.at<uint8_t>(v, u) = u < 80 ? 255 : 0;
        }
    vtloc::io::write_png(depth, d);
    vtloc::io::write_png(mask, m);
}

}  // namespace

TEST_CASE("a depth view becomes the camera-frame cloud the intrinsics say", "[io][api]") {
    const std::string depth = test::temp_path("sphere_depth.png"), mask = test::temp_path("sphere_mask.png");
    write_sphere_depth(depth, mask);
    const api::PointCloud all = api::load_depth_cloud(depth, {kFx, kFy, kCx, kCy});
    const api::PointCloud half = api::load_depth_cloud(depth, {kFx, kFy, kCx, kCy}, mask);
    REQUIRE(all.normals.empty());
    REQUIRE(all.viewpoint.has_value());
    CHECK(half.size() < all.size());
    CHECK(half.size() > all.size() / 3);
    const cv::Mat d = vtloc::io::read_mat(depth);
    size_t i = 0;  // rows in image order
    for (int v = 0; v < 120; ++v)
        for (int u = 0; u < 160; ++u) {
            const uint16_t z = d.at<uint16_t>(v, u);
            if (!z) continue;
            INFO("pixel " << u << "," << v);
            REQUIRE(i < all.size());
            CHECK(all.xyz[i * 3] == float((u - kCx) * z / kFx));
            CHECK(all.xyz[i * 3 + 1] == float((v - kCy) * z / kFy));
            CHECK(all.xyz[i * 3 + 2] == float(z));
            // on the sphere, up to the millimetre rounding of the depth
            const double r = std::sqrt(std::pow(all.xyz[i * 3], 2) + std::pow(all.xyz[i * 3 + 1], 2) +
                                       std::pow(all.xyz[i * 3 + 2] - 400.0, 2));
            CHECK(std::abs(r - 40) < 1.0);
            ++i;
        }
    CHECK(i == all.size());
    for (size_t j = 0; j < half.size(); ++j) CHECK(half.xyz[j * 3] < 0.5f);  // the left half only
}

TEST_CASE("a depth view encodes with normals facing the camera", "[api]") {
    const std::string depth = test::temp_path("sphere_depth2.png"), mask = test::temp_path("sphere_mask2.png");
    write_sphere_depth(depth, mask);
    api::Context ctx(test::validated());
    api::Model model(ctx, test::tiny_model());
    const api::PointCloud cloud = api::load_depth_cloud(depth, {kFx, kFy, kCx, kCy});
    const api::Object obj = model.encode_object(cloud);
    CHECK(obj.normals_estimated());
    CHECK(obj.source_points() == cloud.size());
    const api::PointCloud& c = obj.cloud();
    size_t facing = 0, accurate = 0;
    for (size_t i = 0; i < c.size(); ++i) {
        double to_cam = 0, radial = 0, len = 0;
        for (int a = 0; a < 3; ++a) {
            const double p = c.xyz[i * 3 + size_t(a)], n = c.normals[i * 3 + size_t(a)];
            const double centre = a == 2 ? 400.0 : 0.0;
            to_cam += -p * n;
            radial += (p - centre) * n;
            len += (p - centre) * (p - centre);
        }
        facing += to_cam > 0;
        accurate += radial / std::sqrt(len) > std::cos(10 * 3.14159265 / 180);  // within 10 degrees of the sphere's
    }
    CHECK(facing == c.size());
    CHECK(accurate >= c.size() * 9 / 10);
    test::require_no_validation(ctx);
}

TEST_CASE("a large cloud is reduced to the model's point count, the same on GPU and CPU", "[api]") {
    const int64_t n = 120000;
    api::PointCloud big;
    std::mt19937 rng(5);
    std::normal_distribution<double> g;
    for (int64_t i = 0; i < n; ++i) {
        double v[3] = {g(rng), g(rng), g(rng)};
        const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (double x : v) big.xyz.push_back(float(25 * x / l));
    }
    api::Context ctx(test::validated());
    api::Model model(ctx, test::tiny_model());
    const api::Object gpu = model.encode_object(big);
    const api::Object cpu = model.encode_object(big, {}, api::Backend::Cpu);
    const size_t want = size_t(model.info().sample_points);
    CHECK(gpu.source_points() == size_t(n));
    REQUIRE(gpu.cloud().size() == want);
    CHECK(gpu.cloud().xyz == cpu.cloud().xyz);  // FPS indices are exact on both
    CHECK(gpu.normals_estimated());
    // every kept point is one of the input's
    for (size_t i = 0; i < want; i += 17) {
        const float r = std::sqrt(gpu.cloud().xyz[i * 3] * gpu.cloud().xyz[i * 3] +
                                  gpu.cloud().xyz[i * 3 + 1] * gpu.cloud().xyz[i * 3 + 1] +
                                  gpu.cloud().xyz[i * 3 + 2] * gpu.cloud().xyz[i * 3 + 2]);
        CHECK(std::abs(r - 25.0f) < 1e-3f);
    }
    test::require_no_validation(ctx);
}

TEST_CASE("voxel_reduce keeps at least the target, from the input's own rows", "[api]") {
    HostTensor c({5000, 3});
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-1, 1);
    for (float& x : c.data) x = u(rng);
    const HostTensor r = voxel_reduce(c, 1000);
    CHECK(r.shape[0] >= 1000);
    CHECK(r.shape[0] < 2500);
    CHECK(r.data[0] == c.data[0]);  // the first point is always the first of its voxel
}

TEST_CASE("depth input errors name the file and the problem", "[api]") {
    const std::string depth = test::temp_path("sphere_depth3.png"), mask = test::temp_path("sphere_mask3.png");
    write_sphere_depth(depth, mask);
    const std::string rgb = test::temp_path("rgb_depth.png"), zero = test::temp_path("zero_depth.png"),
                      small = test::temp_path("small_mask.png");
    vtloc::io::write_png(rgb, cv::Mat(120, 160, CV_8UC3, cv::Scalar(1, 2, 3)));
    vtloc::io::write_png(zero, cv::Mat(120, 160, CV_16UC1, cv::Scalar(0)));
    vtloc::io::write_png(small, cv::Mat(10, 10, CV_8UC1, cv::Scalar(255)));
    CHECK_THAT(test::api_error([&] { api::load_depth_cloud(rgb, {kFx, kFy, kCx, kCy}); }),
               Catch::Contains("rgb_depth.png") && Catch::Contains("single-channel 16-bit"));
    CHECK_THAT(test::api_error([&] { api::load_depth_cloud(zero, {kFx, kFy, kCx, kCy}); }),
               Catch::Contains("no pixel has a depth measurement"));
    CHECK_THAT(test::api_error([&] { api::load_depth_cloud(depth, {kFx, kFy, kCx, kCy}, small); }),
               Catch::Contains("small_mask.png") && Catch::Contains("the mask is 10x10"));
    CHECK_THAT(test::api_error([&] { api::load_depth_cloud(depth, {0, kFy, kCx, kCy}); }),
               Catch::Contains("intrinsics"));
    CHECK_THAT(test::api_error([&] { api::load_depth_cloud(depth, {kFx, kFy, kCx, kCy}, "", -1); }),
               Catch::Contains("depth unit"));
    CHECK_THAT(test::api_error([&] { api::load_depth_cloud(test::temp_path("nosuch.png"), {kFx, kFy, kCx, kCy}); }),
               Catch::Contains("nosuch.png"));
}
