#pragma once
// The shipped files every tool defaults to, relative to the data folder (the
// repository, or an install's share/vtloc), and how the tools find that folder:
// the CLI (apps/vtloc/shipped.cpp) and vtloc-bench search the same places and
// measure the same default model.
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "base/error.h"

namespace vtloc {

inline constexpr const char* kDefaultModel = "models/vtloc-lite-everyday.safetensors";
// The untrained export kept as a fixture (tests, the mug examples): the CLI says
// RANDOM WEIGHTS whenever it runs it.
inline constexpr const char* kRandomModel = "models/vtloc-r18-half-random.safetensors";

// Where the data folder may be, in the order searched: $VTLOC_DATA_DIR; beside an
// installed executable, <prefix>/<install_datadir> (prefix/bin/vtloc ->
// prefix/share/vtloc; none when install_datadir is empty); the executable's
// parent folder (build/vtloc -> the repository); the source tree it was built
// from. `exe` is the executable's path (empty where unknown).
inline std::vector<std::filesystem::path> shipped_dir_candidates(const std::filesystem::path& exe,
                                                                 const std::string& install_datadir,
                                                                 const std::string& source_dir) {
    std::vector<std::filesystem::path> dirs;
    if (const char* env = std::getenv("VTLOC_DATA_DIR"); env && *env) dirs.push_back(env);
    if (!exe.empty()) {  // an installed copy uses its own files first
        if (!install_datadir.empty()) dirs.push_back(exe.parent_path().parent_path() / install_datadir);
        dirs.push_back(exe.parent_path().parent_path());
    }
    if (!source_dir.empty()) dirs.push_back(source_dir);
    return dirs;
}

// The first candidate that holds kDefaultModel (a file). Throws vtloc::Error
// naming every folder tried and VTLOC_DATA_DIR.
inline std::filesystem::path find_shipped_dir(const std::vector<std::filesystem::path>& candidates) {
    std::string tried;
    for (const std::filesystem::path& d : candidates) {
        std::error_code ec;
        if (!d.empty() && std::filesystem::is_regular_file(d / kDefaultModel, ec)) return d;
        if (!d.empty()) tried += (tried.empty() ? "" : ", ") + d.string();
    }
    throw Error("cannot find the shipped files (" + std::string(kDefaultModel) + ") in " +
                (tried.empty() ? std::string("no folder") : tried) +
                "; set VTLOC_DATA_DIR to the folder that holds models/ and examples/");
}

// This process's executable (Linux /proc/self/exe; empty elsewhere: the other
// candidates still apply).
inline std::filesystem::path current_executable() {
    std::error_code ec;
    std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    return ec ? std::filesystem::path() : exe;
}

}  // namespace vtloc
