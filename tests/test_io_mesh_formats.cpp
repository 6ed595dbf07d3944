// Mesh input in every supported format (load_mesh) and the PLY mesh writer.
// Fixture files are built byte by byte (tests/mesh_fixtures.h), never by the
// writer under test (except for the writer's own round trip); the readers'
// errors are in test_io_mesh_errors.cpp.
#include <catch2/catch.hpp>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "engine/io/mesh_formats.h"
#include "tests/api_test_util.h"
#include "tests/io_test_util.h"
#include "tests/mesh_fixtures.h"

using namespace vtloc;
using namespace vtloc::io;
using vtloc::test::append_le;
using vtloc::test::require_error;
using vtloc::test::write_temp;
using namespace vtloc::test::mesh;

TEST_CASE("load_mesh reads OFF: quads, comments, face colours", "[io]") {
    require_cube(load_mesh(write_temp("mf_cube.off", off_cube())));
    // Upper-case extension, counts on the keyword line.
    std::string s = "OFF 8 6 0\n";
    for (int i = 0; i < 8; ++i) s += corner_line(i) + "\n";
    for (auto& q : kQuads) s += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) + " " + std::to_string(q[3]) + "\n";
    require_cube(load_mesh(write_temp("mf_cube_same_line.OFF", s)));
}

TEST_CASE("load_mesh reads COFF and NOFF, ignoring colours and normals", "[io]") {
    std::string c = "COFF\n8 12 0\n", n = "NOFF # normals follow each vertex\n8 12 0\n";
    for (int i = 0; i < 8; ++i) {
        c += corner_line(i) + " 0.5 0.5 0.5 1\n";
        n += corner_line(i) + " 0 0 1\n";
    }
    auto tri = cube_triangles();
    for (size_t t = 0; t < 12; ++t) {
        std::string f = "3 " + std::to_string(tri[3 * t]) + " " + std::to_string(tri[3 * t + 1]) + " " +
                        std::to_string(tri[3 * t + 2]) + "\n";
        c += f;
        n += f;
    }
    require_cube(load_mesh(write_temp("mf_cube.coff.off", c)));
    TriangleMesh m = load_mesh(write_temp("mf_cube_noff.off", n));
    require_cube(m);
    CHECK(m.normals.empty());
}

TEST_CASE("load_mesh reads OBJ: v/vt/vn corners, negative indices, other statements", "[io]") {
    std::string s = "# cube\nmtllib cube.mtl\no cube\n";
    for (int i = 0; i < 8; ++i) s += corner_line(i, "v ") + "\n";
    s += "vt 0 0\nvt 1 0\nvn 0 0 1\ng side\nusemtl red\ns off\n";
    const char* forms[] = {"%d", "%d/1", "%d//1", "%d/2/1"};
    for (size_t f = 0; f < kQuads.size(); ++f) {
        s += "f";
        for (int v : kQuads[f]) {
            char buf[32];
            // Alternate absolute and relative (-8 = the first of the 8 vertices) references.
            std::snprintf(buf, sizeof buf, forms[f % 4], f % 2 ? v - 8 : v + 1);
            s += std::string(" ") + buf;
        }
        s += "\n";
    }
    s += "l 1 2\n";
    require_cube(load_mesh(write_temp("mf_cube.obj", s)));
    require_cube(load_mesh(write_temp("mf_cube_upper.Obj", s)));
}

TEST_CASE("load_mesh resolves OBJ relative indices against the vertices read so far", "[io]") {
    // Two triangles, each right after its own three vertices, both as -3 -2 -1.
    TriangleMesh m = load_mesh(write_temp("mf_rel.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"
                                                        "v 0 0 1\nv 1 0 1\nv 0 1 1\nf -3 -2 -1\n"));
    CHECK(m.triangles == std::vector<uint32_t>{0, 1, 2, 3, 4, 5});
    // A pentagon fans into three triangles from its first corner.
    m = load_mesh(write_temp("mf_pent.obj", "v 0 0 0\nv 2 0 0\nv 3 1 0\nv 1 3 0\nv -1 1 0\nf 1 2 3 4 5\n"));
    CHECK(m.triangles == std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4});
}

TEST_CASE("load_mesh reads ascii PLY with extra elements and vertex_index", "[io]") {
    std::string s = "ply\nformat ascii 1.0\ncomment cube\nelement vertex 8\nproperty float x\nproperty float y\n"
                    "property float z\nproperty float nx\nproperty uchar red\nelement face 6\n"
                    "property list uchar int vertex_index\nproperty uchar alpha\nelement edge 2\n"
                    "property list uchar int ends\nend_header\n";
    for (int i = 0; i < 8; ++i) s += corner_line(i) + " 0.5 7\n";
    for (auto& q : kQuads) s += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) + " " + std::to_string(q[3]) + " 9\n";
    s += "2 0 1\n2 1 2\n";
    require_cube(load_mesh(write_temp("mf_cube_ascii.ply", s)));
}

TEST_CASE("load_mesh reads binary PLY in both byte orders and any types", "[io]") {
    require_cube(load_mesh(write_temp("mf_cube_le.ply", ply_binary_cube(false))));
    require_cube(load_mesh(write_temp("mf_cube_be.PLY", ply_binary_cube(true))));
}

TEST_CASE("load_mesh reads ASCII STL and welds equal corners", "[io]") {
    TriangleMesh m = load_mesh(write_temp("mf_cube_ascii.stl", ascii_stl_cube()));
    CHECK(m.vertex_count() == 8);
    require_same_geometry(m, kCorners, cube_triangles());
}

TEST_CASE("load_mesh reads binary STL, also when it starts with 'solid'", "[io]") {
    for (std::string header : {"binary cube", "solid cube exported as binary"}) {
        INFO(header);
        TriangleMesh m = load_mesh(write_temp("mf_cube_bin.stl", binary_stl_cube(header)));
        CHECK(m.vertex_count() == 8);
        require_same_geometry(m, kCorners, cube_triangles());
    }
    // -0 and +0 are equal coordinates, so they weld.
    std::string s(80, ' ');
    append_le<uint32_t>(s, 2);
    const float tris[2][9] = {{0, 0, 0, 1, 0, 0, 0, 1, 0}, {-0.0f, 0, 0, 0, 1, 0, 0, 0, 1}};
    for (auto& t : tris) {
        for (int k = 0; k < 3; ++k) append_le<float>(s, 0);
        for (float v : t) append_le<float>(s, v);
        append_le<uint16_t>(s, 0);
    }
    CHECK(load_mesh(write_temp("mf_zero.STL", s)).vertex_count() == 4);
}

TEST_CASE("load_mesh reads glTF/GLB through load_gltf_mesh", "[io]") {
    const std::string mug = vtloc::test::source_path("examples/mug.glb");
    TriangleMesh a = load_mesh(mug), b = load_gltf_mesh(mug);
    CHECK(a.positions == b.positions);
    CHECK(a.triangle_count() > 100);
    CHECK(a.triangle_count() <= b.triangle_count());
    vtloc::test::GltfBuilder g;
    g.mesh(g.vec3(kCorners), g.u16(vtloc::test::box_triangles()));
    g.node(0);
    g.scene({0});
    require_cube(load_mesh(write_temp("mf_cube_upper.GLB", g.glb())));
}

TEST_CASE("load_mesh drops degenerate triangles and accepts open, non-manifold meshes", "[io]") {
    // 0-1-2 good; 0-0-1 repeated index; 0-1-3 collinear (zero area); quad 0 1 1 2 fans to one
    // repeated-index triangle and one good one.
    TriangleMesh m = load_mesh(write_temp("mf_degen.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n2 0 0\n"
                                                          "3 0 1 2\n3 0 0 1\n3 0 1 3\n4 0 1 1 2\n"));
    CHECK(m.triangles == std::vector<uint32_t>{0, 1, 2, 0, 1, 2});
    CHECK(m.vertex_count() == 4);  // unused vertex 3 stays

    // The cube without its top (+z) face: open boundary.
    std::string s = "OFF\n8 5 0\n";
    for (int i = 0; i < 8; ++i) s += corner_line(i) + "\n";
    for (auto& q : kQuads)
        if (!(q[0] == 4 && q[1] == 5))
            s += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) + " " + std::to_string(q[3]) + "\n";
    CHECK(load_mesh(write_temp("mf_open.off", s)).triangle_count() == 10);

    // Three triangles on one edge: non-manifold.
    m = load_mesh(write_temp("mf_fin.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 2 5\n"));
    CHECK(m.triangle_count() == 3);
}

TEST_CASE("save_mesh_ply writes binary PLY that load_mesh reads back exactly", "[io]") {
    TriangleMesh m;
    m.positions = {0.1f, -2.5e-3f, 3.0f, 1e6f, 0.3333333f, -7.25f, 4.5f, 6e-7f, -0.0f, 1, 2, 3};
    m.triangles = {0, 1, 2, 2, 1, 3, 0, 3, 1};
    const std::string path = vtloc::test::temp_path("mf_saved.ply");
    save_mesh_ply(path, m);
    CHECK_FALSE(std::filesystem::exists(path + ".tmp"));
    TriangleMesh r = load_mesh(path);
    CHECK(r.triangles == m.triangles);
    REQUIRE(r.positions.size() == m.positions.size());
    CHECK(std::memcmp(r.positions.data(), m.positions.data(), m.positions.size() * 4) == 0);
    // The header names the dataset layout exactly.
    std::ifstream in(path, std::ios::binary);
    std::string head((std::istreambuf_iterator<char>(in)), {});
    CHECK(head.rfind("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                     "property float z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n", 0) == 0);

    TriangleMesh bad = m;
    bad.triangles[4] = 9;
    require_error([&] { save_mesh_ply(path, bad); }, {"save_mesh_ply", "out of range"});
}
