// glTF loading and area-weighted surface sampling (SPEC section 1).
#include <catch2/catch.hpp>
#include <cmath>

#include "engine/io/mesh.h"
#include "engine/io/object.h"
#include "engine/io/splitmix64.h"
#include "tests/io_test_util.h"

using namespace vtloc;
using namespace vtloc::io;
using vtloc::test::GltfBuilder;
using vtloc::test::require_error;
using vtloc::test::write_temp;

namespace {

double norm3(const float* v) { return std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]); }

// Every sample of an axis-aligned box with half sizes h (centred at c) lies on
// a face, with the face's outward unit normal.
void require_on_box(const HostTensor& pts, const double h[3], const double c[3]) {
    for (int64_t i = 0; i < pts.shape[0]; ++i) {
        const float* p = &pts.data[size_t(i) * 6];
        INFO("sample " << i << ": " << p[0] << " " << p[1] << " " << p[2] << " n " << p[3] << " " << p[4] << " " << p[5]);
        REQUIRE(norm3(p + 3) == Approx(1.0).margin(1e-6));
        int face_axis = -1;
        for (int a = 0; a < 3; ++a) {
            double d = p[a] - c[a];
            REQUIRE(std::abs(d) <= h[a] + 1e-4);
            if (std::abs(std::abs(d) - h[a]) < 1e-4 && std::abs(p[3 + a]) > 0.999) {
                face_axis = a;
                REQUIRE(p[3 + a] * d > 0);  // outward
            }
        }
        REQUIRE(face_axis >= 0);
    }
}

GltfBuilder box_builder(float hx, float hy, float hz) {
    GltfBuilder b;
    int pos = b.vec3(vtloc::test::box_corners(hx, hy, hz));
    int idx = b.u16(vtloc::test::box_triangles());
    b.mesh(pos, idx);
    return b;
}

}  // namespace

TEST_CASE("SplitMix64 matches the reference sequence", "[io]") {
    // First outputs for seed 0 of the published SplitMix64 (also weights_tools/synthetic.py).
    SplitMix64 r(0);
    CHECK(r.next_u64() == 0xE220A8397B1DCDAFull);
    CHECK(r.next_u64() == 0x6E789E6AA1B965F4ull);
    CHECK(r.next_u64() == 0x06C45D188009454Full);
}

TEST_CASE("surface sampling is deterministic and depends on the seed", "[io]") {
    TriangleMesh m;
    m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    m.triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    HostTensor a = sample_surface(m, 500, 7), b = sample_surface(m, 500, 7), c = sample_surface(m, 500, 8);
    CHECK(a.shape == Shape{500, 6});
    CHECK(a.data == b.data);
    CHECK(a.data != c.data);
}

TEST_CASE("a mesh's bounds: its vertices' box, its centre and largest side", "[io]") {
    TriangleMesh m;
    m.positions = {-2, 1, 0.5f, 3, -1, 0.5f, 0, 4, -0.25f};
    m.triangles = {0, 1, 2};
    const MeshBounds b = bounds(m);
    CHECK(b.lo == std::array<double, 3>{-2, -1, -0.25});
    CHECK(b.hi == std::array<double, 3>{3, 4, 0.5});
    CHECK(b.centre() == std::array<double, 3>{0.5, 1.5, 0.125});
    CHECK(b.largest_side() == 5.0);
    const MeshBounds none = bounds(TriangleMesh{});  // no vertex: an empty box, lo above hi
    CHECK(none.lo[0] > none.hi[0]);
    CHECK(none.largest_side() < 0);
}

TEST_CASE("surface sampling weights triangles by area", "[io]") {
    // Two triangles in z = 0 with areas 1 : 3 (x < 0 and x > 1 apart), face normal +z.
    TriangleMesh m;
    m.positions = {-2, 0, 0, -1, 0, 0, -2, 2, 0, /**/ 2, 0, 0, 5, 0, 0, 2, 2, 0};
    m.triangles = {0, 1, 2, 3, 4, 5};
    const int n = 20000;
    HostTensor s = sample_surface(m, n, 123);
    int right = 0;
    for (int i = 0; i < n; ++i) {
        const float* p = &s.data[size_t(i) * 6];
        REQUIRE(p[2] == 0.0f);
        REQUIRE(p[5] == 1.0f);
        bool in_left = p[0] >= -2 && p[0] <= -1 && p[1] >= 0 && p[1] <= 2 * (-1 - p[0]) + 1e-5;
        bool in_right = p[0] >= 2 && p[0] <= 5 && p[1] >= 0 && p[1] <= 2 * (5 - p[0]) / 3 + 1e-5;
        REQUIRE((in_left || in_right));
        right += in_right;
    }
    // Expected 3/4; binomial sd = sqrt(n * 3/16) ~ 61 samples: allow 5 sd.
    CHECK(std::abs(right - 0.75 * n) < 5 * std::sqrt(n * 3.0 / 16));
}

TEST_CASE("surface sampling interpolates vertex normals where the mesh has them", "[io]") {
    TriangleMesh m;
    m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    m.triangles = {0, 1, 2};
    float s = float(1 / std::sqrt(2.0));
    m.normals = {s, 0, s, s, 0, s, 0, s, s};  // differ from the face normal (0, 0, 1)
    HostTensor pts = sample_surface(m, 200, 1);
    for (int i = 0; i < 200; ++i) {
        const float* p = &pts.data[size_t(i) * 6];
        REQUIRE(norm3(p + 3) == Approx(1.0).margin(1e-6));
        // The sample is (w1, w2, 0): vertices 0 and 1 share a normal, so it is (1 - y) n0 + y n2.
        double nx = (1 - p[1]) * s, ny = p[1] * s, nz = s, l = std::sqrt(nx * nx + ny * ny + nz * nz);
        REQUIRE(p[3] == Approx(nx / l).margin(1e-5));
        REQUIRE(p[4] == Approx(ny / l).margin(1e-5));
    }
}

TEST_CASE("GLB box: indexed triangles with a node transform sample onto the surface", "[io]") {
    GltfBuilder b = box_builder(2, 1, 0.5f);
    // Translate, rotate 90 degrees about z (x -> y) and scale 3: a box of half sizes (3, 6, 1.5) at (10, 0, -5).
    float q = float(std::sqrt(0.5));
    b.node(0, {{"translation", {10, 0, -5}}, {"rotation", {0, 0, q, q}}, {"scale", {3, 3, 3}}});
    b.scene({0});
    std::string path = write_temp("box.glb", b.glb());
    TriangleMesh m = load_gltf_mesh(path);
    CHECK(m.triangle_count() == 12);
    CHECK(m.normals.empty());
    HostTensor pts = load_object(path, 2000, 5);
    CHECK(pts.shape == Shape{2000, 6});
    const double h[3] = {3, 6, 1.5}, c[3] = {10, 0, -5};
    require_on_box(pts, h, c);
    CHECK(load_object(path, 2000, 5).data == pts.data);
}

TEST_CASE("glTF: non-indexed primitives, mirrored and nested nodes, external buffer", "[io]") {
    GltfBuilder b;
    std::vector<float> corners = vtloc::test::box_corners(1, 1, 1), soup;
    for (uint16_t i : vtloc::test::box_triangles()) soup.insert(soup.end(), &corners[3 * i], &corners[3 * i] + 3);
    int mesh = b.mesh(b.vec3(soup));  // no indices
    // Parent mirrors x (scale -1: winding must flip to keep normals outward), child moves by +4 in y.
    int child = b.node(mesh, {{"translation", {0, 4, 0}}});
    b.doc["nodes"].push_back({{"scale", {-1, 1, 1}}, {"children", {child}}});
    b.scene({1});
    std::string path = b.write_gltf("soup.gltf");
    TriangleMesh m = load_gltf_mesh(path);
    CHECK(m.triangle_count() == 12);
    HostTensor pts = sample_surface(m, 1000, 3);
    const double h[3] = {1, 1, 1}, c[3] = {0, 4, 0};
    require_on_box(pts, h, c);
}

TEST_CASE("glTF vertex normals are transformed and used", "[io]") {
    GltfBuilder b;
    int pos = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    int nrm = b.vec3({0, 0, 1, 0, 0, 1, 0, 0, 1});
    int mesh = b.mesh(pos, b.u32({0, 1, 2}), nrm);
    float q = float(std::sqrt(0.5));
    b.node(mesh, {{"rotation", {q, 0, 0, q}}});  // 90 degrees about x: +z -> -y
    b.scene({0});
    HostTensor pts = load_object(write_temp("normals.glb", b.glb()), 50);
    for (int i = 0; i < 50; ++i) {
        const float* p = &pts.data[size_t(i) * 6];
        REQUIRE(p[3] == Approx(0).margin(1e-6));
        REQUIRE(p[4] == Approx(-1).margin(1e-6));
        REQUIRE(p[5] == Approx(0).margin(1e-6));
        REQUIRE(p[1] == Approx(0).margin(1e-6));
    }
}

TEST_CASE("glTF errors name the file and the problem", "[io]") {
    require_error([] { load_gltf_mesh(vtloc::test::temp_path("does_not_exist.glb")); },
                  {"does_not_exist.glb", "no such file"});
    std::string junk = write_temp("junk.gltf", "this is not json");
    require_error([&] { load_gltf_mesh(junk); }, {"junk.gltf", "not a valid glTF file"});
    {
        std::string glb = box_builder(1, 1, 1).glb();
        std::string cut = write_temp("cut.glb", glb.substr(0, glb.size() - 40));
        require_error([&] { load_gltf_mesh(cut); }, {"cut.glb", "not a valid glTF file"});
    }
    {
        GltfBuilder b;
        b.mesh(b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0}), -1, -1, 0);  // POINTS
        b.node(0);
        b.scene({0});
        require_error([&] { load_gltf_mesh(write_temp("points.glb", b.glb())); },
                      {"points.glb", "no triangles", "1 primitives of other modes skipped"});
    }
    {
        GltfBuilder b;
        b.mesh(b.vec3({0, 0, 0, 1, NAN, 0, 0, 1, 0}));
        b.node(0);
        b.scene({0});
        require_error([&] { load_gltf_mesh(write_temp("nan.glb", b.glb())); },
                      {"nan.glb", "vertex 1 has a non-finite coordinate"});
    }
    {
        GltfBuilder b;
        b.mesh(b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0}), -1, b.vec3({0, 0, 1, 0, 0, 1, 0, 0, 0}));
        b.node(0);
        b.scene({0});
        require_error([&] { load_gltf_mesh(write_temp("zero_normal.glb", b.glb())); },
                      {"zero_normal.glb", "normal of vertex 2 is zero"});
    }
    {
        GltfBuilder b;
        b.mesh(b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0}), b.u16({0, 1, 3}));
        b.node(0);
        b.scene({0});
        require_error([&] { load_gltf_mesh(write_temp("bad_index.glb", b.glb())); },
                      {"bad_index.glb", "index 2 refers to vertex 3 of 3"});
    }
    {
        TriangleMesh flat;
        flat.positions = {0, 0, 0, 1, 0, 0, 2, 0, 0};
        flat.triangles = {0, 1, 2};
        require_error([&] { sample_surface(flat, 10, 0, "flat.glb"); }, {"flat.glb", "no triangle with non-zero area"});
    }
    require_error([] { load_object(write_temp("object.foo", "v 0 0 0\n"), 10); }, {"object.foo", "unknown object file type"});
}
