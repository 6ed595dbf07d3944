#pragma once
// One exception type for every user-facing failure: bad files, bad shapes,
// Vulkan errors. The message names the problem; callers print it and exit.
#include <stdexcept>
#include <string>

namespace vtloc {

class Error : public std::runtime_error {
public:
    explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace vtloc
