#include "tests/golden.h"

#include <catch2/catch.hpp>
#include <filesystem>

namespace vtloc::test {

HostTensor Golden::f32(const std::string& name) const {
    const TensorInfo& t = file_.at(name);
    return HostTensor(t.shape, file_.to_f32(t));
}

std::vector<int32_t> Golden::i32(const std::string& name) const { return file_.to_i32(file_.at(name)); }

void Golden::compare(const std::string& name, const HostTensor& got, Tolerance tol) const {
    require_close(got, f32(name), tol, "golden '" + name + "' from " + file_.source());
}

void Golden::compare_exact(const std::string& name, const std::vector<int32_t>& got) const {
    std::vector<int32_t> want = i32(name);
    INFO("golden '" << name << "' from " << file_.source());
    REQUIRE(got.size() == want.size());
    size_t first_diff = got.size();
    for (size_t i = 0; i < got.size(); ++i)
        if (got[i] != want[i]) { first_diff = i; break; }
    INFO("first difference at " << first_diff << (first_diff < got.size()
             ? ": got " + std::to_string(got[first_diff]) + ", want " + std::to_string(want[first_diff]) : ""));
    CHECK(first_diff == got.size());
}

std::string goldens_dir() { return VTLOC_SOURCE_DIR "/weights_tools/goldens"; }

std::string build_goldens_dir() { return VTLOC_BUILD_GOLDENS_DIR; }

std::string require_golden_file(const std::string& dir, const std::string& name) {
    std::string path = dir + "/" + name;
    INFO("golden file " << path << " is missing; `ctest --test-dir build -R goldens.paper` writes the "
         "paper-size ones, `/usr/bin/python3 -m weights_tools.make_goldens` the committed ones");
    REQUIRE(std::filesystem::exists(path));
    return path;
}

}  // namespace vtloc::test
