// The shipped examples/ load, and each example's contact lies on the mug.
#include <catch2/catch.hpp>
#include <fstream>
#include <nlohmann/json.hpp>

#include "engine/io/candidates.h"
#include "engine/io/image.h"
#include "engine/io/object.h"
#include "tests/io_test_util.h"

using namespace vtloc;
using namespace vtloc::io;

TEST_CASE("shipped examples: mug, touches, contacts on the mesh, candidates", "[io]") {
    const std::string dir = std::string(VTLOC_SOURCE_DIR) + "/examples/";
    TriangleMesh mesh = load_gltf_mesh(dir + "mug.glb");
    CHECK(mesh.triangle_count() > 1000);
    CHECK(mesh.normals.size() == mesh.positions.size());
    HostTensor cloud = sample_surface(mesh, 1024, kDefaultSampleSeed, "mug.glb");
    for (int64_t i = 0; i < 1024; ++i) {
        const float* p = &cloud.data[size_t(i) * 6];
        REQUIRE((p[1] >= 0 && p[1] <= 97.01f && std::abs(p[2]) <= 40.01f && p[0] >= -40.01f && p[0] <= 54.3f));
    }
    HostTensor cands = load_candidates(dir + "mug_candidates.csv");
    CHECK(cands.shape == Shape{12, 3});
    for (int k = 1; k <= 3; ++k) {
        std::string name = "touch_0" + std::to_string(k);
        INFO(name);
        std::ifstream in(dir + name + ".json");
        REQUIRE(in);
        nlohmann::json j = nlohmann::json::parse(in);
        RgbImage img = load_tactile_image(dir + j.at("tactile").get<std::string>());
        CHECK((img.height == 120 && img.width == 160));
        auto c = j.at("contact").get<std::vector<float>>();
        // The contact is a mesh vertex, hence exactly on the surface, and the k-th candidate.
        bool on_mesh = false;
        for (size_t v = 0; v < mesh.vertex_count(); ++v)
            on_mesh = on_mesh || (mesh.positions[3 * v] == c[0] && mesh.positions[3 * v + 1] == c[1] &&
                                  mesh.positions[3 * v + 2] == c[2]);
        CHECK(on_mesh);
        for (int a = 0; a < 3; ++a) CHECK(cands.data[size_t(k - 1) * 3 + size_t(a)] == Approx(c[size_t(a)]).margin(1e-4));
    }
    std::ifstream readme(dir + "README.md");
    std::string text((std::istreambuf_iterator<char>(readme)), std::istreambuf_iterator<char>());
    CHECK(text.find("Creative Commons Attribution 4.0") != std::string::npos);
    CHECK(text.find("ObjectFolder 2.0") != std::string::npos);
}
