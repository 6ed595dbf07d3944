#pragma once
// Shared by the libFuzzer targets: the input as a file (the readers take paths),
// and the rule every target enforces: bad input ends in vtloc::Error; any other
// exception escaping is a finding (libFuzzer reports the abort).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

namespace vtloc::fuzz {

// A per-process file in /dev/shm (RAM), rewritten for every input.
inline std::string write_input(const uint8_t* data, size_t size, const std::string& ext) {
    const std::string path = "/dev/shm/vtloc-fuzz-" + std::to_string(getpid()) + ext;
    if (FILE* f = std::fopen(path.c_str(), "wb")) {
        if (size) std::fwrite(data, 1, size, f);
        std::fclose(f);
    }
    return path;
}

}  // namespace vtloc::fuzz
