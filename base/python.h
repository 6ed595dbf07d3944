#pragma once
// The Python (with torch) that the benches and tests run: $VTLOC_PYTHON where set
// (a packed device check sets it), else `configured`, the VTLOC_PYTHON that CMake
// was given (a compile definition of those targets).
#include <cstdlib>
#include <string>

namespace vtloc {

inline std::string python_interpreter(const char* configured) {
    const char* env = std::getenv("VTLOC_PYTHON");
    return env && *env ? env : configured;
}

}  // namespace vtloc
