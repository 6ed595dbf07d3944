// Point clouds as robots' tools write them: PCD (ascii and binary, as PCL
// writes them), PLY without normals, x y z text rows; and meshes of the
// dataset formats through load_object. Files are written byte by byte here.
#include <catch2/catch.hpp>

#include <cmath>

#include "engine/io/object.h"
#include "tests/io_test_util.h"

using namespace vtloc;
using namespace vtloc::io;
using vtloc::test::append_le;
using vtloc::test::require_error;
using vtloc::test::write_temp;

namespace {

const std::string kPcdHead3 =
    "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\n"
    "COUNT 1 1 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\n";

}  // namespace

TEST_CASE("PCD ascii and binary give the same cloud, and NaN points are dropped", "[io]") {
    const std::string ascii = kPcdHead3 + "DATA ascii\n1 2 3 4278190080\nnan nan nan 0\n-0.5 0.25 7 16\n";
    std::string bin = kPcdHead3 + "DATA binary\n";
    for (float v : {1.0f, 2.0f, 3.0f}) append_le(bin, v);
    append_le(bin, uint32_t(4278190080u));
    for (float v : {NAN, NAN, NAN}) append_le(bin, v);
    append_le(bin, uint32_t(0));
    for (float v : {-0.5f, 0.25f, 7.0f}) append_le(bin, v);
    append_le(bin, uint32_t(16));
    const HostTensor a = load_object(write_temp("a.pcd", ascii), 100), b = load_object(write_temp("b.pcd", bin), 100);
    REQUIRE(a.shape == Shape{2, 3});
    CHECK(a.data == std::vector<float>{1, 2, 3, -0.5f, 0.25f, 7});
    CHECK(b.data == a.data);
}

TEST_CASE("PCD with normals (PCL's PointNormal layout) keeps them, unit length", "[io]") {
    std::string s =
        "VERSION 0.7\nFIELDS x y z normal_x normal_y normal_z curvature\nSIZE 4 4 4 4 4 4 8\nTYPE F F F F F F F\n"
        "COUNT 1 1 1 1 1 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary\n";
    for (float v : {1.0f, 2.0f, 3.0f, 0.0f, 0.0f, 2.0f}) append_le(s, v);
    append_le(s, 0.5);
    const HostTensor c = load_object(write_temp("n.pcd", s), 100);
    REQUIRE(c.shape == Shape{1, 6});
    CHECK(c.data == std::vector<float>{1, 2, 3, 0, 0, 1});
}

TEST_CASE("PLY without normals and text rows are xyz clouds, text with six columns keeps normals", "[io]") {
    const HostTensor p = load_object(write_temp("nonormals.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                                                "property float y\nproperty float z\nend_header\n1 2 3\n4 5 6\n"),
                                     100);
    REQUIRE(p.shape == Shape{2, 3});
    CHECK(p.data == std::vector<float>{1, 2, 3, 4, 5, 6});
    const HostTensor t = load_object(write_temp("pts.xyz", "x y z\n1 2 3\n4,5,6\n"), 100);
    CHECK(t.data == p.data);
    const HostTensor n = load_object(write_temp("pts.csv", "1,2,3,0,3,0\n"), 100);
    REQUIRE(n.shape == Shape{1, 6});
    CHECK(n.data == std::vector<float>{1, 2, 3, 0, 1, 0});
}

TEST_CASE("a PLY with faces and OBJ/OFF meshes are sampled like glTF meshes", "[io]") {
    const std::string tri = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    const HostTensor a = load_object(write_temp("tri.ply", tri), 50);
    const HostTensor b = load_object(write_temp("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), 50);
    const HostTensor c = load_object(write_temp("tri.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), 50);
    REQUIRE(a.shape == Shape{50, 6});
    CHECK(a.data == b.data);
    CHECK(a.data == c.data);
    for (int64_t i = 0; i < 50; ++i) CHECK(std::abs(a.data[size_t(i * 6 + 5)]) == 1.0f);  // the triangle's normal
}

TEST_CASE("cloud file errors name the file and the problem", "[io]") {
    require_error([] { load_object(write_temp("zip.pcd", kPcdHead3 + "DATA binary_compressed\n"), 10); },
                  {"zip.pcd", "binary_compressed", "not supported"});
    require_error([] { load_object(write_temp("short.pcd", kPcdHead3 + "DATA binary\n\x01\x02"), 10); },
                  {"short.pcd", "ends before its 3 points"});
    require_error([] { load_object(write_temp("nodata.pcd", kPcdHead3), 10); }, {"nodata.pcd", "no DATA line"});
    // Fuzzer finding (tests/fuzz, fuzz_points): a binary PCD whose DATA line ends the file
    // without a newline read past the end of the buffer.
    require_error([] { load_object(write_temp("eof.pcd", kPcdHead3 + "DATA binary\t\xff\xff"), 10); },
                  {"eof.pcd", "ends before its 3 points"});
    require_error([] { load_object(write_temp("noxyz.pcd", "FIELDS a b\nSIZE 4 4\nTYPE F F\nPOINTS 1\nDATA ascii\n1 2\n"), 10); },
                  {"noxyz.pcd", "no x y z fields"});
    require_error([] { load_object(write_temp("badsize.pcd", "FIELDS x y z\nSIZE 4 4\n"), 10); },
                  {"badsize.pcd", "line 2", "SIZE has 2 values for 3 fields"});
    require_error([] { load_object(write_temp("word.pcd", kPcdHead3 + "DATA ascii\n1 2 x 0\n"), 10); },
                  {"word.pcd", "point 0", "'x' is not a number"});
    require_error([] { load_object(write_temp("allnan.pcd", "FIELDS x y z\nPOINTS 1\nDATA ascii\nnan nan nan\n"), 10); },
                  {"allnan.pcd", "no point with measured (non-NaN) coordinates"});
    require_error([] { load_object(write_temp("nan.xyz", "1 2 3\n1 nan 3\n"), 10); }, {"nan.xyz", "line 2", "non-finite"});
    require_error([] { load_object(write_temp("empty.xyz", "# nothing\n"), 10); }, {"empty.xyz", "no points in the file"});
    require_error([] {
        load_object(write_temp("nan.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                          "property float z\nend_header\n1 nan 2\n"), 10);
    }, {"nan.ply", "point 0", "non-finite"});
}
