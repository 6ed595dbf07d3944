// base/shipped.h: where the CLI and vtloc-bench look for the shipped model and
// examples, in which order, and what they say when no folder holds them.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include "base/error.h"
#include "base/shipped.h"

using namespace vtloc;
namespace fs = std::filesystem;

namespace {

// VTLOC_DATA_DIR set (or unset, for nullptr) for one scope.
struct DataDirEnv {
    std::string old;
    bool had;
    explicit DataDirEnv(const char* v) {
        const char* o = std::getenv("VTLOC_DATA_DIR");
        had = o != nullptr;
        if (had) old = o;
        if (v) setenv("VTLOC_DATA_DIR", v, 1);
        else unsetenv("VTLOC_DATA_DIR");
    }
    ~DataDirEnv() {
        if (had) setenv("VTLOC_DATA_DIR", old.c_str(), 1);
        else unsetenv("VTLOC_DATA_DIR");
    }
};

// A folder that holds a (fake) default model.
fs::path data_folder(const fs::path& d) {
    fs::create_directories((d / kDefaultModel).parent_path());
    std::ofstream(d / kDefaultModel) << "x";
    return d;
}

}  // namespace

TEST_CASE("shipped files: the folders searched, in order", "[shipped]") {
    const fs::path exe = "/opt/vt/bin/vtloc";
    {
        DataDirEnv env(nullptr);
        CHECK(shipped_dir_candidates(exe, "share/vtloc", "/src") ==
              std::vector<fs::path>{"/opt/vt/share/vtloc", "/opt/vt", "/src"});
        CHECK(shipped_dir_candidates(exe, "", "/src") == std::vector<fs::path>{"/opt/vt", "/src"});  // the bench
        CHECK(shipped_dir_candidates("", "share/vtloc", "/src") == std::vector<fs::path>{"/src"});  // no /proc
        CHECK(shipped_dir_candidates("", "share/vtloc", "").empty());
    }
    DataDirEnv env("/data");
    CHECK(shipped_dir_candidates(exe, "share/vtloc", "/src") ==
          std::vector<fs::path>{"/data", "/opt/vt/share/vtloc", "/opt/vt", "/src"});
}

TEST_CASE("shipped files: the first folder holding the default model wins, and none is an error naming each", "[shipped]") {
    const fs::path root = fs::temp_directory_path() / ("vtloc-shipped-" + std::to_string(::getpid()));
    fs::remove_all(root);
    const fs::path empty = root / "empty", a = data_folder(root / "a"), b = data_folder(root / "b");
    fs::create_directories(empty);
    fs::create_directories(root / "dir_model" / kDefaultModel);  // a folder named like the model is not one
    CHECK(find_shipped_dir({empty, a, b}) == a);
    CHECK(find_shipped_dir({"", root / "dir_model", b, a}) == b);
    try {
        find_shipped_dir({empty, root / "missing", root / "dir_model"});
        FAIL("no folder holds the model, and no error");
    } catch (const Error& e) {
        const std::string msg = e.what();
        CHECK_THAT(msg, Catch::Contains(std::string("cannot find the shipped files (") + kDefaultModel + ")"));
        CHECK_THAT(msg, Catch::Contains(empty.string() + ", " + (root / "missing").string()));
        CHECK_THAT(msg, Catch::Contains("set VTLOC_DATA_DIR"));
    }
    CHECK_THROWS_WITH(find_shipped_dir({}), Catch::Contains("in no folder"));
    fs::remove_all(root);
}

TEST_CASE("shipped files: this build finds the repository's model", "[shipped]") {
    DataDirEnv env(nullptr);
    const fs::path d = find_shipped_dir(shipped_dir_candidates(current_executable(), "", VTLOC_SOURCE_DIR));
    CHECK(fs::is_regular_file(d / kDefaultModel));
    CHECK(fs::is_regular_file(d / "examples" / "mug.glb"));  // the bench's default object sits beside it
}
