// Candidate contact points from CSV/text and PLY files.
#include <catch2/catch.hpp>

#include "engine/io/candidates.h"
#include "tests/io_test_util.h"

using namespace vtloc;
using namespace vtloc::io;
using vtloc::test::require_error;
using vtloc::test::write_temp;

TEST_CASE("candidates from CSV with a header, comments and extra columns", "[io]") {
    std::string path = write_temp("cands.csv",
                                  "# candidates on the mug\n"
                                  "x, y, z, label_id\n"
                                  "1.5, 2, -3, 7   # first\n"
                                  "\n"
                                  "4e1,5,6,8\r\n"
                                  "  -0.25 ,0,1e-3,9\n");
    HostTensor c = load_candidates(path);
    REQUIRE(c.shape == Shape{3, 3});
    CHECK(c.data == std::vector<float>{1.5f, 2, -3, 40, 5, 6, -0.25f, 0, 1e-3f});
}

TEST_CASE("candidates from white-space text and from PLY", "[io]") {
    HostTensor t = load_candidates(write_temp("cands.txt", "1 2 3\n4\t5 6\n"));
    CHECK(t.data == std::vector<float>{1, 2, 3, 4, 5, 6});
    HostTensor p = load_candidates(write_temp("cands.ply", "ply\nformat ascii 1.0\nelement vertex 2\n"
                                                           "property float x\nproperty float y\nproperty float z\n"
                                                           "property float nx\nend_header\n1 2 3 9\n4 5 6 9\n"));
    CHECK(p.shape == Shape{2, 3});
    CHECK(p.data == std::vector<float>{1, 2, 3, 4, 5, 6});
}

TEST_CASE("candidate errors name the file, the line and the problem", "[io]") {
    require_error([] { load_candidates(vtloc::test::temp_path("missing.csv")); }, {"missing.csv", "no such file"});
    require_error([] { load_candidates(write_temp("c_word.csv", "x,y,z\n1,2,3\n4,five,6\n")); },
                  {"c_word.csv", "line 3", "'five' is not a number"});
    require_error([] { load_candidates(write_temp("c_short.csv", "1,2\n")); }, {"c_short.csv", "line 1", "need x, y, z"});
    require_error([] { load_candidates(write_temp("c_ragged.csv", "1,2,3\n1,2,3,4\n")); },
                  {"c_ragged.csv", "line 2", "4 values, but line 1 has 3"});
    require_error([] { load_candidates(write_temp("c_inf.csv", "1,2,inf\n")); }, {"c_inf.csv", "line 1", "non-finite"});
    require_error([] { load_candidates(write_temp("c_empty.csv", "# nothing\nx,y,z\n")); },
                  {"c_empty.csv", "no candidate points"});
    require_error([] { load_candidates(write_temp("c_empty.ply", "ply\nformat ascii 1.0\nelement vertex 0\n"
                                                                 "property float x\nproperty float y\nproperty float z\nend_header\n")); },
                  {"c_empty.ply", "no candidate points"});
    require_error([] { load_candidates(write_temp("c_noz.ply", "ply\nformat ascii 1.0\nelement vertex 1\n"
                                                               "property float x\nproperty float y\nend_header\n1 2\n")); },
                  {"c_noz.ply", "no property 'z'"});
}
