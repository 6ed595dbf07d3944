// The shipped examples/ load: each mug example's contact lies on the mug, and the demo's tour is consistent.
#include <catch2/catch.hpp>
#include <fstream>
#include <nlohmann/json.hpp>

#include "engine/io/candidates.h"
#include "engine/io/image.h"
#include "engine/io/mesh_formats.h"
#include "engine/io/object.h"
#include "engine/io/touch_sequence.h"
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

TEST_CASE("shipped examples: the demo's potato tour reads, its truths lie on the mesh and follow its motions", "[io]") {
    const std::string dir = std::string(VTLOC_SOURCE_DIR) + "/examples/";
    const TouchSequence seq = read_touch_sequence(dir + "potato_tour.json");
    REQUIRE(seq.touches.size() == 8);
    CHECK(seq.object_diameter_mm > 90);
    const TriangleMesh mesh = load_mesh(seq.object);
    const HostTensor dense = sample_surface(mesh, 200000, kDefaultSampleSeed, "potato");
    const auto motions = seq.relative_motions("potato_tour.json");
    for (size_t k = 0; k < seq.touches.size(); ++k) {
        INFO("touch " << k + 1);
        const RgbImage img = load_tactile_image(seq.touches[k].tactile);
        CHECK((img.height == 120 && img.width == 160));
        REQUIRE(seq.touches[k].contact);
        const auto& c = *seq.touches[k].contact;
        // On the surface: 200,000 samples of ~30,000 mm^2 lie ~0.4 mm apart, so the nearest is within 0.5 mm.
        double best = 1e30;
        for (int64_t i = 0; i < dense.shape[0]; ++i) {
            const float* p = &dense.data[size_t(i) * 6];
            best = std::min(best, std::hypot(p[0] - c[0], p[1] - c[1], p[2] - c[2]));
        }
        CHECK(best < 0.5);
        if (k == 0) continue;
        // The sensor's move and the contact's move differ only by the press and the tilt (<= 1.5 mm, 5 degrees
        // at 20 mm from the window centre): their lengths agree within 3 mm.
        const auto& p = *seq.touches[k - 1].contact;
        const double hop = std::hypot(c[0] - p[0], c[1] - p[1], c[2] - p[2]);
        CHECK(std::abs(hop - std::hypot(motions[k]->t[0], motions[k]->t[1], motions[k]->t[2])) < 3);
    }
}
