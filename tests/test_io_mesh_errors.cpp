// load_mesh's errors: bad files, truncated bodies, absurd counts, bad indices
// and coordinates, and corrupted files that must fail without crashing.
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
#include "tests/mesh_fixtures.h"

using namespace vtloc;
using namespace vtloc::io;
using vtloc::test::require_error;
using vtloc::test::write_temp;
using namespace vtloc::test::mesh;

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
