// The touches file reader (engine/io/touch_sequence): both motion forms, the
// relative motions it forms, and one-line errors naming the file and the touch.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>

#include "engine/io/touch_sequence.h"
#include "engine/rigid.h"
#include "tests/io_test_util.h"

using namespace vtloc;

namespace {

io::TouchSequence parse(const std::string& text) { return io::parse_touch_sequence(text, "/data", "seq.json"); }

// A rotation by `deg` about z and a translation, as 4x4 JSON rows.
std::string matrix(double deg, double x, double y, double z) {
    const double c = std::cos(deg * M_PI / 180), s = std::sin(deg * M_PI / 180);
    return "[[" + std::to_string(c) + "," + std::to_string(-s) + ",0," + std::to_string(x) + "],[" + std::to_string(s) + "," +
           std::to_string(c) + ",0," + std::to_string(y) + "],[0,0,1," + std::to_string(z) + "],[0,0,0,1]]";
}

std::string relative(const std::string& second_motion) {
    return R"({"format": "vtloc-touches/2", "motion": "relative", "touches": [{"tactile": "a.png"},
              {"tactile": "sub/b.png", "motion": )" + second_motion + "}]}";
}

}  // namespace

TEST_CASE("touches file: relative motions as 4x4 or {Q, q}, paths resolved, truths read", "[io][touches]") {
    const io::TouchSequence s = parse(R"({"format": "vtloc-touches/2", "object": "o.ply", "object_diameter_mm": 80,
        "touches": [{"tactile": "a.png", "contact": [1, 2, 3]},
                    {"tactile": "b.png", "motion": )" + matrix(90, 5, 6, 7) + R"(},
                    {"tactile": "c.png", "motion": {"Q": [[1,0,0],[0,1,0],[0,0,1]], "q": [0, 10, 0]}}]})");
    REQUIRE(s.touches.size() == 3);
    CHECK(s.touches[1].tactile == "/data/b.png");
    CHECK(s.object == "/data/o.ply");
    CHECK(s.object_diameter_mm == 80);
    REQUIRE(s.touches[0].contact);
    CHECK((*s.touches[0].contact)[2] == 3);
    CHECK(!s.touches[1].contact);
    const auto m = s.relative_motions("seq.json");
    CHECK(!m[0]);
    REQUIRE(m[1]);
    CHECK(m[1]->R[1] == Approx(-1).margin(1e-6));  // 90 degrees about z: R = [[0, -1], [1, 0]]
    CHECK(m[1]->t[2] == 7);
    CHECK(m[2]->t[1] == 10);
}

TEST_CASE("touches file: flange poses and a tool give the sensor's relative motions", "[io][touches]") {
    // tool: 10 mm along the flange's z; flange 2 = flange 1 turned 90 degrees about z, 20 mm along x.
    const io::TouchSequence s = parse(R"({"format": "vtloc-touches/2", "motion": "flange", "tool": )" + matrix(0, 0, 0, 10) +
                                      R"(, "touches": [{"tactile": "a.png", "flange": )" + matrix(0, 0, 0, 0) +
                                      R"(}, {"tactile": "b.png", "flange": )" + matrix(90, 20, 0, 0) + "}]}");
    const auto m = s.relative_motions("seq.json");
    REQUIRE(m[1]);
    // The sensor sits on the flange's axis, so it moves as the flange does.
    CHECK(m[1]->t[0] == Approx(20).margin(1e-9));
    CHECK(m[1]->t[2] == Approx(0).margin(1e-9));
    CHECK(m[1]->R[3] == Approx(1).margin(1e-6));
    io::TouchSequence no_tool = s;
    no_tool.tool.reset();
    test::require_error([&] { no_tool.relative_motions("seq.json"); }, {"seq.json", "flange poses need the tool"});
}

TEST_CASE("touches file: bad files fail in one line naming the file and the touch", "[io][touches][errors]") {
    using test::require_error;
    require_error([] { parse("{"); }, {"seq.json", "not valid JSON"});
    require_error([] { parse(R"({"touches": [{"tactile": "a.png"}]})"); }, {"seq.json", "old translation-only"});
    require_error([] { parse(R"({"format": "vtloc-touches/1", "touches": []})"); }, {"seq.json", "is not \"vtloc-touches/2\""});
    require_error([] { parse(R"({"format": "vtloc-touches/2", "touches": []})"); }, {"seq.json", "no touches"});
    require_error([] { parse(relative("[1, 2, 3]")); }, {"seq.json: touch 2", "old translation-only format"});
    require_error([] { parse(relative("[[1,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]")); }, {"touch 2's motion", "4 rows of 4"});
    // Scaled: columns of length 2.
    require_error([] { parse(relative(R"({"Q": [[2,0,0],[0,2,0],[0,0,2]], "q": [0,0,0]})")); },
                  {"seq.json: touch 2's motion", "not a rotation"});
    require_error([] { parse(relative(R"({"Q": [[-1,0,0],[0,1,0],[0,0,1]], "q": [0,0,0]})")); },
                  {"touch 2's motion", "reflection"});
    // JSON has no NaN or inf; an overflowing number is refused by the parser, naming it.
    require_error([] { parse(relative(R"({"Q": [[1,0,0],[0,1,0],[0,0,1]], "q": [0,1e999,0]})")); },
                  {"seq.json: not valid JSON", "1e999"});
    require_error([] { parse(relative(R"({"Q": [[1,0,0],[0,1,0],[0,0,1]], "q": [0,"x",0]})")); },
                  {"touch 2's motion", "expected a number"});
    require_error([] { parse(relative(R"([[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,1,1]])")); }, {"last row must be 0 0 0 1"});
    require_error([] { parse(R"({"format": "vtloc-touches/2", "touches": [{"tactile": "a.png", "motion": )" + matrix(0, 1, 0, 0) + "}]}"); },
                  {"touch 1", "first touch has no previous one"});
    require_error([] { parse(R"({"format": "vtloc-touches/2", "touches": [{"tactile": "a.png"}, {"tactile": "b.png"}]})"); },
                  {"seq.json: touch 2", "needs a \"motion\""});
    require_error([] { parse(R"({"format": "vtloc-touches/2", "touches": [{"image": "a.png"}]})"); },
                  {"seq.json: touch 1", "\"tactile\""});
    require_error([] { parse(R"({"format": "vtloc-touches/2", "motion": "flange", "touches": [{"tactile": "a.png"}]})"); },
                  {"touch 1", "needs \"flange\""});
    require_error([] { parse(R"({"format": "vtloc-touches/2", "motion": "world", "touches": [{"tactile": "a.png"}]})"); },
                  {"\"motion\" must be"});
    require_error([] { parse(R"({"format": "vtloc-touches/2", "touches": [{"tactile": "a.png", "contact": [1, 2]}]})"); },
                  {"touch 1", "\"contact\" must be [x, y, z]"});
    require_error([] { io::read_touch_sequence("/no/such/seq.json"); }, {"/no/such/seq.json", "no such file"});
    // A directory opens as an empty stream: named as one, not as bad JSON.
    const std::string dir = test::temp_path("a_touches_dir");
    std::filesystem::create_directories(dir);
    require_error([&] { io::read_touch_sequence(dir); }, {dir, "is a directory, not a file"});
}

TEST_CASE("a 4x4 given row by row: a NaN or inf anywhere is named as one, before the last row's check", "[io][touches][errors]") {
    // JSON cannot hold one and the CLI's --tool refuses 'nan' when parsing; the check guards other callers.
    std::array<double, 16> v{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    CHECK(rigid_from_rows(v, "m").t == std::array<double, 3>{0, 0, 0});
    v[15] = NAN;
    test::require_error([&] { rigid_from_rows(v, "m"); }, {"m: row 3, column 3 holds NaN or inf"});
    v[15] = 1, v[6] = INFINITY;
    test::require_error([&] { rigid_from_rows(v, "m"); }, {"m: row 1, column 2 holds NaN or inf"});
}
