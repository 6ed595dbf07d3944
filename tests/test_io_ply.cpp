// PLY reading (ascii, binary little/big endian, any numeric type, extra
// properties and elements) and writing, as weights_tools/ply.py reads them.
#include <catch2/catch.hpp>
#include <cmath>

#include "engine/io/colormap.h"
#include "engine/io/heatmap_ply.h"
#include "engine/io/mesh_formats.h"
#include "engine/io/object.h"
#include "engine/io/ply.h"
#include "tests/io_test_util.h"

using namespace vtloc;
using namespace vtloc::io;
using vtloc::test::append_le;
using vtloc::test::require_error;
using vtloc::test::write_temp;

namespace {

HostTensor test_cloud() {
    // Awkward floats on purpose: they must survive the ascii form bit for bit.
    return HostTensor({3, 6}, std::vector<float>{1e-30f, -0.0f, 123456.789f, 0, 0, 1,      //
                                                 0.1f, -2.5f, 3.3333333f, 0.6f, 0.8f, 0,  //
                                                 -7, 1e7f, 2.2e-7f, 0, -1, 0});
}

const char* kAsciiCloud =
    "ply\r\n"
    "format ascii 1.0\n"
    "comment written by hand\n"
    "element vertex 2\n"
    "property double x\nproperty float y\nproperty int z\n"
    "property uchar red\n"
    "property list uchar int vertex_indices\n"
    "property float nx\nproperty float ny\nproperty short nz\n"
    "element face 1\n"
    "property list uchar int vertex_indices\n"
    "end_header\n"
    "1.5 -2 3 255 2 7 8 0 0 1\n"
    "\n"
    "+4 5e-1 -6 0 0 0 3 0\n"  // normal (0, 3, 0): normalised on load
    "3 0 1 0\n";

}  // namespace

TEST_CASE("PLY round trip, binary and ascii, with heat-map columns", "[io]") {
    HostTensor cloud = test_cloud();
    for (PlyFormat f : {PlyFormat::BinaryLittleEndian, PlyFormat::Ascii}) {
        std::string path = vtloc::test::temp_path(f == PlyFormat::Ascii ? "rt_ascii.ply" : "rt_binary.ply");
        write_heatmap_ply(path, cloud, std::vector<float>{0.0f, 0.25f, 1.0f}, f);
        PlyVertices v = read_ply_vertices(path);
        CHECK(v.names == std::vector<std::string>{"x", "y", "z", "nx", "ny", "nz", "contact_prob", "red", "green", "blue"});
        HostTensor back = ply_columns(v, {"x", "y", "z", "nx", "ny", "nz"}, path);
        CHECK(back.shape == cloud.shape);
        for (size_t i = 0; i < cloud.data.size(); ++i) {
            INFO(i);
            CHECK(std::memcmp(&back.data[i], &cloud.data[i], 4) == 0);  // bit for bit (-0.0 included)
        }
        CHECK(v.values[6] == 0.0);
        CHECK(v.values[10 + 6] == 0.25);
        CHECK(v.values[20 + 6] == 1.0);
        auto colour = heat_color(0.25f);
        for (int c = 0; c < 3; ++c) CHECK(v.values[10 + 7 + size_t(c)] == colour[size_t(c)]);
        CHECK(load_ply_cloud(path).data == cloud.data);
    }
}

TEST_CASE("PLY reader: ascii with mixed types, extra properties, lists and elements", "[io]") {
    std::string path = write_temp("mixed.ply", kAsciiCloud);
    HostTensor c = load_ply_cloud(path);
    REQUIRE(c.shape == Shape{2, 6});
    CHECK(c.data == std::vector<float>{1.5f, -2, 3, 0, 0, 1, 4, 0.5f, -6, 0, 1, 0});
}

TEST_CASE("PLY reader: binary big endian and an element before the vertices", "[io]") {
    std::string s = "ply\nformat binary_big_endian 1.0\nelement camera 1\nproperty list uchar float k\n"
                    "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                    "property double nx\nproperty double ny\nproperty double nz\nproperty uint flags\nend_header\n";
    auto be = [&s](auto v) {
        char b[sizeof v];
        std::memcpy(b, &v, sizeof v);
        for (size_t i = sizeof v; i-- > 0;) s.push_back(b[i]);
    };
    s.push_back(char(2));  // camera: a list of two floats to skip
    be(1.0f), be(2.0f);
    for (int i = 0; i < 2; ++i) {
        be(float(i + 1)), be(float(-i)), be(0.5f);
        be(0.0), be(0.0), be(i ? -1.0 : 1.0);
        be(uint32_t(0xDEADBEEF));
    }
    HostTensor c = load_ply_cloud(write_temp("big.ply", s));
    CHECK(c.data == std::vector<float>{1, 0, 0.5f, 0, 0, 1, 2, -1, 0.5f, 0, 0, -1});
}

TEST_CASE("PLY errors name the file and the problem", "[io]") {
    auto ply = [](const std::string& name, const std::string& text) { return write_temp(name, text); };
    const std::string head = "ply\nformat ascii 1.0\nelement vertex 2\n"
                             "property float x\nproperty float y\nproperty float z\n"
                             "property float nx\nproperty float ny\nproperty float nz\nend_header\n";
    require_error([] { load_ply_cloud(vtloc::test::temp_path("nope.ply")); }, {"nope.ply", "no such file"});
    require_error([&] { load_ply_cloud(ply("notply.ply", "solid cube\nfacet normal 0 0 1\n")); },
                  {"notply.ply", "not a PLY file"});
    require_error([&] { load_ply_cloud(ply("badtype.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n")); },
                  {"badtype.ply", "malformed PLY header, line 4", "unknown type 'quad'"});
    require_error([&] { load_ply_cloud(ply("badcount.ply", "ply\nformat ascii 1.0\nelement vertex many\nend_header\n")); },
                  {"badcount.ply", "line 3", "element count"});
    require_error([&] { load_ply_cloud(ply("noend.ply", "ply\nformat ascii 1.0\nelement vertex 1\n")); },
                  {"noend.ply", "no end_header"});
    require_error([&] { load_ply_cloud(ply("noformat.ply", "ply\nelement vertex 0\nend_header\n")); },
                  {"noformat.ply", "no format line"});
    require_error([&] { load_ply_cloud(ply("novertex.ply", "ply\nformat ascii 1.0\nelement face 0\nend_header\n")); },
                  {"novertex.ply", "no vertex element"});
    require_error([&] { load_ply_cloud(ply("short_ascii.ply", head + "0 0 0 0 0 1\n")); },
                  {"short_ascii.ply", "truncated", "after 1 of 2 rows"});
    require_error([&] { load_ply_cloud(ply("fewvalues.ply", head + "0 0 0 0 0 1\n1 1 1 0 1\n")); },
                  {"fewvalues.ply", "line 12", "too few values"});
    require_error([&] { load_ply_cloud(ply("word.ply", head + "0 0 0 0 0 1\n1 one 1 0 1 0\n")); },
                  {"word.ply", "line 12", "'one' is not a number"});
    require_error([&] { load_ply_cloud(ply("nan.ply", head + "0 0 0 0 0 1\n1 nan 1 0 1 0\n")); },
                  {"nan.ply", "point 1 has a non-finite coordinate"});
    require_error([&] { load_ply_cloud(ply("zeronormal.ply", head + "0 0 0 0 0 1\n1 1 1 0 0 0\n")); },
                  {"zeronormal.ply", "point 1 has a zero normal"});
    require_error([&] { load_ply_cloud(ply("nonormals.ply", "ply\nformat ascii 1.0\nelement vertex 1\n"
                                                             "property float x\nproperty float y\nproperty float z\n"
                                                             "end_header\n1 2 3\n")); },
                  {"nonormals.ply", "no normals"});
    {
        std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                          "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n";
        for (int i = 0; i < 6 * 2 + 3; ++i) append_le<float>(bin, 1.0f);  // 2.5 of 3 vertices
        require_error([&] { load_ply_cloud(ply("short_bin.ply", bin)); },
                      {"short_bin.ply", "truncated", "after 2 of 3 rows"});
    }
    {
        HostTensor c = load_ply_cloud(ply("two.ply", head + "0 0 0 0 0 1\n1 1 1 0 1 0\n"));
        require_points(c, 2, "two.ply");
        require_error([&] { require_points(c, 1024, "two.ply"); },
                      {"two.ply", "the object has 2 points, the model needs at least 1024"});
    }
}

TEST_CASE("the cloud and mesh readers read one PLY header: the same errors, the same leniencies", "[io]") {
    // Until 2026-12-06 each reader parsed the header its own way (the mesh reader's errors did
    // not quote the line; only it took a last header line without a newline, only the cloud
    // reader a format line without its version).
    const std::string body = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                             "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const std::string data = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    struct Bad {
        std::string text, expect;
    };
    for (const Bad& b : {Bad{"ply\nformat ascii 1.0\nelement vertex many\n", "line 3 'element vertex many': element count"},
                         Bad{"ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int v\n",
                             "line 4 'property list float int v': a list count must have an integer type"},
                         Bad{"ply\nformat utf8 1.0\n", "line 2 'format utf8 1.0': unknown format 'utf8'"},
                         Bad{"ply\nformat ascii 1.0\nvertices 3\n", "line 3 'vertices 3': unknown keyword 'vertices'"},
                         Bad{"ply\nformat ascii 1.0\nelement vertex 1\n", "no end_header"},
                         Bad{"ply \nformat ascii 1.0\n", "not a PLY file"}}) {
        const std::string path = write_temp("shared_header.ply", b.text);
        INFO(b.text);
        require_error([&] { load_ply_cloud(path); }, {"shared_header.ply", b.expect});
        require_error([&] { load_mesh(path); }, {"shared_header.ply", b.expect});
    }
    // A format line without its version; the header's last line without a newline (no data).
    const std::string lenient = write_temp("lenient.ply", "ply\r\nformat ascii\r\n" + body + data);
    CHECK(read_ply_vertices(lenient).count == 3);
    CHECK(load_mesh(lenient).triangle_count() == 1);
    const std::string empty_cloud = write_temp("empty_cloud.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n"
                                                                  "property float y\nproperty float z\nend_header");
    CHECK(read_ply_vertices(empty_cloud).count == 0);
}
