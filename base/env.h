#pragma once
// A switch from the environment: on for 1, on, true or yes (any case), off when
// unset or anything else. Header-only, below every layer.
#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <string>

namespace vtloc {

inline bool env_flag(const char* name) {
    const char* v = std::getenv(name);
    if (!v) return false;
    std::string s(v);
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s == "1" || s == "on" || s == "true" || s == "yes";
}

}  // namespace vtloc
