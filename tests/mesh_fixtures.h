#pragma once
// The cube fixtures of the mesh-format tests (test_io_mesh_formats.cpp,
// test_io_mesh_errors.cpp): files built byte by byte, never by a writer under test.
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "engine/io/mesh.h"
#include "tests/io_test_util.h"

namespace vtloc::test::mesh {

using io::TriangleMesh;
using vtloc::test::append_le;

// The unit cube of io_test_util (corners +-1) as 6 quads, each fanning into
// the two triangles box_triangles() lists for it.
inline const std::vector<float> kCorners = vtloc::test::box_corners(1, 1, 1);
inline const std::vector<std::vector<int>> kQuads = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                              {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

inline std::vector<uint32_t> cube_triangles() {
    auto t = vtloc::test::box_triangles();
    return {t.begin(), t.end()};
}

inline std::string num(float v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

inline std::string corner_line(int i, const char* prefix = "") {
    return prefix + num(kCorners[3 * i]) + " " + num(kCorners[3 * i + 1]) + " " + num(kCorners[3 * i + 2]);
}

inline void require_cube(const TriangleMesh& m) {
    CHECK(m.positions == kCorners);
    CHECK(m.triangles == cube_triangles());
}

template <class T>
inline void append_be(std::string& s, T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    for (size_t i = sizeof(T); i-- > 0;) s.push_back(b[i]);
}

inline std::string off_cube() {
    std::string s = "OFF\n# a cube, quads with face colours\n\n8 6 12\n";
    for (int i = 0; i < 8; ++i) s += corner_line(i) + "\n";
    for (auto& q : kQuads) s += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) +
                                " " + std::to_string(q[3]) + "  255 0 0\n";
    return s;
}

inline std::string ascii_stl_cube(const char* name = "cube") {
    auto tri = cube_triangles();
    std::string s = std::string("solid ") + name + "\n";
    for (size_t t = 0; t < 12; ++t) {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for (int c = 0; c < 3; ++c) s += corner_line(int(tri[3 * t + c]), "      vertex ") + "\n";
        s += "    endloop\n  endfacet\n";
    }
    return s + "endsolid " + name + "\n";
}

inline std::string binary_stl_cube(const std::string& header80) {
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
inline void require_same_geometry(const TriangleMesh& m, const std::vector<float>& pos, const std::vector<uint32_t>& tri) {
    REQUIRE(m.triangles.size() == tri.size());
    for (size_t i = 0; i < tri.size(); ++i)
        for (int k = 0; k < 3; ++k) CHECK(m.positions[3 * m.triangles[i] + k] == pos[3 * tri[i] + k]);
}

inline std::string ply_binary_cube(bool big) {
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

}  // namespace vtloc::test::mesh
