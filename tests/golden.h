#pragma once
// Reads a golden file written by `python3 -m weights_tools.golden` (tensor
// names of SPEC section 8) and compares engine tensors against it.
#include <string>
#include <vector>

#include "engine/safetensors.h"
#include "tests/harness.h"

namespace vtloc::test {

class Golden {
public:
    explicit Golden(const std::string& path) : file_(SafetensorsFile::load(path)) {}

    bool has(const std::string& name) const { return file_.find(name) != nullptr; }
    HostTensor f32(const std::string& name) const;
    std::vector<int32_t> i32(const std::string& name) const;
    Shape shape(const std::string& name) const { return file_.at(name).shape; }
    const SafetensorsFile& file() const { return file_; }

    // fp32 comparison with a stated tolerance (shape must match exactly).
    void compare(const std::string& name, const HostTensor& got, Tolerance tol = {}) const;
    // Integer outputs (indices) must match exactly.
    void compare_exact(const std::string& name, const std::vector<int32_t>& got) const;

private:
    SafetensorsFile file_;
};

// The directory holding committed goldens (weights_tools/goldens).
std::string goldens_dir();
// The directory where the CTest fixture `goldens.paper` writes the paper-size
// weights and goldens (vtloc-r18, vtloc-mcr): build/goldens.
std::string build_goldens_dir();
// Loads `dir/name`, failing the test with a hint when the file is missing.
std::string require_golden_file(const std::string& dir, const std::string& name);

}  // namespace vtloc::test
