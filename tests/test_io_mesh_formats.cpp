// Mesh input in every supported format (load_mesh) and the PLY mesh writer.
// Fixture files are built here byte by byte, never by the writer under test
// (except for the writer's own round trip).
#include <catch2/catch.hpp>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "engine/io/mesh_formats.h"
#include "engine/io/mesh_formats_detail.h"
#include "engine/io/splitmix64.h"
#include "tests/api_test_util.h"
#include "tests/io_test_util.h"

using namespace vtloc;
using namespace vtloc::io;
using vtloc::test::append_le;
using vtloc::test::require_error;
using vtloc::test::write_temp;

namespace {

// The unit cube of io_test_util (corners +-1) as 6 quads, each fanning into
// the two triangles box_triangles() lists for it.
const std::vector<float> kCorners = vtloc::test::box_corners(1, 1, 1);
const std::vector<std::vector<int>> kQuads = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                              {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

std::vector<uint32_t> cube_triangles() {
    auto t = vtloc::test::box_triangles();
    return {t.begin(), t.end()};
}

std::string num(float v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

std::string corner_line(int i, const char* prefix = "") {
    return prefix + num(kCorners[3 * i]) + " " + num(kCorners[3 * i + 1]) + " " + num(kCorners[3 * i + 2]);
}

void require_cube(const TriangleMesh& m) {
    CHECK(m.positions == kCorners);
    CHECK(m.triangles == cube_triangles());
}

template <class T>
void append_be(std::string& s, T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    for (size_t i = sizeof(T); i-- > 0;) s.push_back(b[i]);
}

std::string off_cube() {
    std::string s = "OFF\n# a cube, quads with face colours\n\n8 6 12\n";
    for (int i = 0; i < 8; ++i) s += corner_line(i) + "\n";
    for (auto& q : kQuads) s += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) +
                                " " + std::to_string(q[3]) + "  255 0 0\n";
    return s;
}

std::string ascii_stl_cube(const char* name = "cube") {
    auto tri = cube_triangles();
    std::string s = std::string("solid ") + name + "\n";
    for (size_t t = 0; t < 12; ++t) {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for (int c = 0; c < 3; ++c) s += corner_line(int(tri[3 * t + c]), "      vertex ") + "\n";
        s += "    endloop\n  endfacet\n";
    }
    return s + "endsolid " + name + "\n";
}

std::string binary_stl_cube(const std::string& header80) {
    std::string s = header80;
    s.resize(80, ' ');
    append_le<uint32_t>(s, 12);
    auto tri = cube_triangles();
    for (size_t t = 0; t < 12; ++t) {
        for (int k = 0; k < 3; ++k) append_le<float>(s, 0.0f);
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k) append_le<float>(s, kCorners[3 * tri[3 * t + c] + k]);
        append_le<uint16_t>(s, 0);
    }
    return s;
}

// STL corners are welded in first-seen order: compare triangle by triangle geometry.
void require_same_geometry(const TriangleMesh& m, const std::vector<float>& pos, const std::vector<uint32_t>& tri) {
    REQUIRE(m.triangles.size() == tri.size());
    for (size_t i = 0; i < tri.size(); ++i)
        for (int k = 0; k < 3; ++k) CHECK(m.positions[3 * m.triangles[i] + k] == pos[3 * tri[i] + k]);
}

std::string ply_binary_cube(bool big) {
    std::string s = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\ncomment two vertex types and extra properties\n"
                    "element vertex 8\nproperty double x\nproperty float y\nproperty short z\nproperty uchar red\n"
                    "property list uchar float uv\n"
                    "element face 6\nproperty ushort flags\nproperty list ushort uint vertex_indices\n"
                    "element edge 1\nproperty int a\nproperty int b\nend_header\n";
    auto put = [&](auto v) { big ? append_be(s, v) : append_le(s, v); };
    for (int i = 0; i < 8; ++i) {
        put(double(kCorners[3 * i]));
        put(float(kCorners[3 * i + 1]));
        put(int16_t(kCorners[3 * i + 2]));
        put(uint8_t(200));
        put(uint8_t(2));
        put(0.5f);
        put(0.25f);
    }
    for (auto& q : kQuads) {
        put(uint16_t(7));
        put(uint16_t(4));
        for (int v : q) put(uint32_t(v));
    }
    put(int32_t(0));
    put(int32_t(1));
    return s;
}

}  // namespace

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

TEST_CASE("load_mesh errors: files, extensions, headers", "[io]") {
    require_error([] { load_mesh(vtloc::test::temp_path("mf_no_such_file.obj")); }, {"mf_no_such_file.obj", "no such file"});
    const std::string xyz = write_temp("mf_cloud.xyz", "0 0 0\n");
    require_error([&] { load_mesh(xyz); }, {"mf_cloud.xyz", "unknown mesh extension '.xyz'", ".off", ".obj", ".ply", ".stl", ".gltf", ".glb"});
    require_error([] { load_mesh(write_temp("mf_empty.stl", "")); }, {"mf_empty.stl", "empty"});
    require_error([] { load_mesh(write_temp("mf_bad.off", "OFF\nabc def\n")); }, {"mf_bad.off", "malformed OFF header", "line 2"});
    require_error([] { load_mesh(write_temp("mf_bad2.off", "MESH\n")); }, {"not an OFF file"});
    require_error([] { load_mesh(write_temp("mf_4d.off", "4OFF\n")); }, {"unsupported OFF variant"});
    require_error([] { load_mesh(write_temp("mf_bad.ply", "ply\nformat ascii 1.0\nelement vertex x\nend_header\n")); },
                  {"mf_bad.ply", "malformed PLY header", "line 3"});
    require_error([] { load_mesh(write_temp("mf_bad2.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n")); },
                  {"no end_header"});
    require_error([] { load_mesh(write_temp("mf_notply.ply", "PLY\n")); }, {"not a PLY file"});
    require_error([] { load_mesh(write_temp("mf_noz.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                                          "property float y\nend_header\n0 0\n")); },
                  {"no scalar property 'z'"});
    require_error([] { load_mesh(write_temp("mf_nofacelist.ply",
                                            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                            "property float z\nelement face 1\nproperty int i\nend_header\n0 0 0\n1 0 0\n0 1 0\n1\n")); },
                  {"vertex_indices"});
    require_error([] { load_mesh(write_temp("mf_short.stl", "not an stl")); }, {"mf_short.stl", "not an STL file"});
    require_error([] { load_mesh(write_temp("mf_bad.stl", "solid x\n facet normal 0 0 1\n  inner loop\n")); },
                  {"line 3", "'outer loop'"});
}

TEST_CASE("load_mesh errors: truncated bodies and absurd counts fail fast", "[io]") {
    require_error([] { load_mesh(write_temp("mf_trunc.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n")); }, {"mf_trunc.off", "truncated"});
    require_error([] { load_mesh(write_temp("mf_trunc2.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")); },
                  {"truncated", "1 of 2 faces"});
    require_error([] { load_mesh(write_temp("mf_shortface.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n")); },
                  {"line 6", "face 0", "4 vertices announced"});
    std::string ply = ply_binary_cube(false);
    require_error([&] { load_mesh(write_temp("mf_trunc.ply", ply.substr(0, ply.size() - 20))); }, {"mf_trunc.ply", "truncated"});
    std::string ascii_ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n";
    require_error([&] { load_mesh(write_temp("mf_trunc_ascii.ply", ascii_ply)); }, {"truncated"});
    std::string stl = binary_stl_cube("cube");
    require_error([&] { load_mesh(write_temp("mf_trunc.stl", stl.substr(0, stl.size() - 7))); },
                  {"mf_trunc.stl", "truncated binary STL", "12 triangles"});
    std::string astl = ascii_stl_cube();
    require_error([&] { load_mesh(write_temp("mf_trunc_ascii.stl", astl.substr(0, astl.find("endloop")))); },
                  {"truncated ASCII STL"});

    // Header counts far beyond what the file can hold: refused before any allocation.
    require_error([] { load_mesh(write_temp("mf_huge.off", "OFF\n1000000000000 1 0\n0 0 0\n")); },
                  {"mf_huge.off", "1000000000000 vertices", "absurd"});
    require_error([] { load_mesh(write_temp("mf_huge.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\n"
                                                           "property float x\nproperty float y\nproperty float z\n"
                                                           "element face 1\nproperty list uchar int vertex_indices\nend_header\n")); },
                  {"mf_huge.ply", "1000000000000 'vertex' rows", "absurd"});
    std::string huge_stl(80, ' ');
    append_le<uint32_t>(huge_stl, 0xFFFFFFFFu);
    require_error([&] { load_mesh(write_temp("mf_huge.stl", huge_stl)); }, {"4294967295 triangles", "truncated"});
    // A face claiming 2^32 - 1 corners in a small binary PLY.
    std::string face_ply = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                           "property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n";
    for (int i = 0; i < 9; ++i) append_le<float>(face_ply, float(i == 3 || i == 7));
    append_le<uint32_t>(face_ply, 0xFFFFFFFFu);
    append_le<int32_t>(face_ply, 0);
    require_error([&] { load_mesh(write_temp("mf_huge_face.ply", face_ply)); }, {"truncated", "element 'face' row 0"});
    // Same in ascii.
    std::string aface = ascii_ply.substr(0, ascii_ply.size() - 6) + "3000000000000000 0 1 2\n";
    require_error([&] { load_mesh(write_temp("mf_huge_face_ascii.ply", aface)); }, {"truncated"});
}

TEST_CASE("load_mesh errors: indices, coordinates, no faces", "[io]") {
    const std::string tri3 = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n";
    require_error([&] { load_mesh(write_temp("mf_range.off", tri3 + "3 0 1 9\n")); },
                  {"mf_range.off", "line 6", "vertex index 9 out of range (3 vertices)"});
    require_error([&] { load_mesh(write_temp("mf_neg.off", tri3 + "3 0 1 -1\n")); }, {"vertex index -1 out of range"});
    require_error([] { load_mesh(write_temp("mf_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n")); },
                  {"mf_range.obj", "line 5", "vertex index 4 out of range (3 vertices)"});
    require_error([] { load_mesh(write_temp("mf_rel.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n")); },
                  {"line 3", "relative vertex index -3 out of range"});
    require_error([] { load_mesh(write_temp("mf_zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")); }, {"index 0"});
    require_error([] { load_mesh(write_temp("mf_range.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                                            "property float y\nproperty float z\nelement face 2\n"
                                                            "property list uchar int vertex_indices\nend_header\n"
                                                            "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 3\n")); },
                  {"mf_range.ply", "face 1", "vertex index 3 out of range"});

    require_error([&] { load_mesh(write_temp("mf_nan.off", "OFF\n3 1 0\n0 0 0\n1 0 0\nnan 1 0\n3 0 1 2\n")); },
                  {"mf_nan.off", "vertex 2", "line 5", "not finite"});
    require_error([] { load_mesh(write_temp("mf_inf.obj", "v 0 0 0\nv 1 -inf 0\nv 0 1 0\nf 1 2 3\n")); },
                  {"mf_inf.obj", "vertex 2", "not finite"});
    std::string stl = binary_stl_cube("cube");
    float qnan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(&stl[84 + 50 * 3 + 12 + 12 * 1 + 4], &qnan, 4);  // triangle 3, corner 1, y
    require_error([&] { load_mesh(write_temp("mf_nan.stl", stl)); }, {"mf_nan.stl", "triangle 3 vertex 1", "not finite"});
    std::string ply = ply_binary_cube(false);
    double inf = std::numeric_limits<double>::infinity();
    const size_t data = ply.find("end_header\n") + 11, row = 8 + 4 + 2 + 1 + 1 + 8;
    std::memcpy(&ply[data + 5 * row], &inf, 8);  // vertex 5's x
    require_error([&] { load_mesh(write_temp("mf_inf.ply", ply)); }, {"mf_inf.ply", "vertex 5", "not finite"});

    require_error([&] { load_mesh(write_temp("mf_big.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 2e7 0\n3 0 1 2\n")); },
                  {"mf_big.off", "vertex 2", "absurd size"});
    require_error([&] { load_mesh(write_temp("mf_huge_coord.obj", "v 0 0 0\nv 1e400 0 0\nv 0 1 0\nf 1 2 3\n")); },
                  {"vertex 2", "absurd size"});

    require_error([] { load_mesh(write_temp("mf_nofaces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n")); }, {"mf_nofaces.off", "no faces"});
    require_error([] { load_mesh(write_temp("mf_nofaces.obj", "v 0 0 0\nv 1 0 0\nvn 0 0 1\n")); }, {"no faces"});
    require_error([] { load_mesh(write_temp("mf_cloud.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                                            "property float y\nproperty float z\nend_header\n0 0 0\n")); },
                  {"mf_cloud.ply", "no faces"});
    std::string empty_stl(80, ' ');
    append_le<uint32_t>(empty_stl, 0);
    require_error([&] { load_mesh(write_temp("mf_nofaces.stl", empty_stl)); }, {"no faces"});
    require_error([] { load_mesh(write_temp("mf_flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n")); },
                  {"mf_flat.obj", "only degenerate triangles"});
    require_error([] { load_mesh(write_temp("mf_twocorner.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n")); }, {"line 3", "at least 3"});
    require_error([] { load_mesh(write_temp("mf_word.off", "OFF\n3 1 0\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n")); },
                  {"line 4", "'zero' is not a number"});
}

TEST_CASE("load_mesh never crashes on truncated or corrupted files", "[io]") {
    std::string ply_ascii = "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                            "element face 6\nproperty list uchar int vertex_indices\nend_header\n";
    for (int i = 0; i < 8; ++i) ply_ascii += corner_line(i) + "\n";
    for (auto& q : kQuads) ply_ascii += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) + " " + std::to_string(q[3]) + "\n";
    std::string obj;
    for (int i = 0; i < 8; ++i) obj += corner_line(i, "v ") + "\n";
    for (auto& q : kQuads) obj += "f " + std::to_string(q[0] + 1) + " " + std::to_string(q[1] + 1) + " " + std::to_string(q[2] + 1) + " " + std::to_string(q[3] + 1) + "\n";
    const std::pair<const char*, std::string> files[] = {
        {"off", off_cube()},           {"obj", obj},
        {"ply", ply_ascii},            {"ply", ply_binary_cube(false)},
        {"ply", ply_binary_cube(true)}, {"stl", ascii_stl_cube()},
        {"stl", binary_stl_cube("solid")}};
    SplitMix64 rng(7);
    size_t loaded = 0, refused = 0;
    // The format readers are called on the bytes directly: thousands of temp files would cost seconds.
    for (auto& [ext, good] : files) {
        const std::string name = std::string("fuzz.") + ext;
        auto reader = ext == std::string("off")   ? detail::load_off
                      : ext == std::string("obj") ? detail::load_obj
                      : ext == std::string("ply") ? detail::load_ply_mesh
                                                  : detail::load_stl;
        auto attempt = [&](const std::string& bytes) {
            try {
                TriangleMesh m = reader(name, std::vector<uint8_t>(bytes.begin(), bytes.end()));
                for (uint32_t id : m.triangles) REQUIRE(id < m.vertex_count());
                ++loaded;
            } catch (const vtloc::Error&) {
                ++refused;
            }
        };
        for (size_t len = 0; len < good.size(); ++len) attempt(good.substr(0, len));
        for (int trial = 0; trial < 2000; ++trial) {
            std::string bad = good;
            for (int k = 0; k < 1 + int(rng.next_u64() % 3); ++k) {
                size_t at = size_t(rng.next_u64() % bad.size());
                const char pool[] = {'\0', '\xff', '9', '-', ' ', '\n', '#', '/', 'e', '\x7f'};
                bad[at] = (rng.next_u64() & 1) ? pool[rng.next_u64() % sizeof pool] : char(rng.next_u64());
            }
            attempt(bad);
        }
    }
    CHECK(refused > 0);
    CHECK(loaded > 0);
}
