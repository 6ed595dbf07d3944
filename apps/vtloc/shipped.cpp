// Finding the shipped model and examples from any working directory.
#include <cstdlib>
#include <system_error>

#include "apps/vtloc/cli.h"

#ifndef VTLOC_SOURCE_DIR
#define VTLOC_SOURCE_DIR ""
#endif
#ifndef VTLOC_INSTALL_DATADIR
#define VTLOC_INSTALL_DATADIR "share/vtloc"
#endif

namespace vtloc::cli {

namespace fs = std::filesystem;

namespace {

fs::path executable_dir() {
    std::error_code ec;
    fs::path exe = fs::read_symlink("/proc/self/exe", ec);  // Linux; elsewhere the other places still work
    return ec ? fs::path() : exe.parent_path();
}

bool holds_shipped(const fs::path& dir) {
    std::error_code ec;
    return !dir.empty() && fs::is_regular_file(dir / kDefaultModel, ec);
}

}  // namespace

fs::path shipped_dir() {
    std::vector<fs::path> tried;
    if (const char* env = std::getenv("VTLOC_DATA_DIR"); env && *env) tried.push_back(env);
    // Beside the executable first, so an installed copy uses its own files.
    if (fs::path exe = executable_dir(); !exe.empty()) {
        tried.push_back(exe.parent_path() / VTLOC_INSTALL_DATADIR);  // prefix/bin/vtloc -> prefix/share/vtloc
        tried.push_back(exe.parent_path());                          // build/vtloc -> the repository
    }
    tried.push_back(VTLOC_SOURCE_DIR);
    std::string list;
    for (const fs::path& d : tried) {
        if (holds_shipped(d)) return d;
        if (!d.empty()) list += (list.empty() ? "" : ", ") + d.string();
    }
    throw api::Error("cannot find the shipped files (" + std::string(kDefaultModel) + ") in " + list +
                     "; set VTLOC_DATA_DIR to the folder that holds models/ and examples/");
}

std::string default_model_path() { return (shipped_dir() / kDefaultModel).string(); }

// By name: a copy of the shipped random file is just as untrained.
bool is_shipped_random_model(const std::string& path) {
    return fs::path(path).filename() == fs::path(kRandomModel).filename();
}

}  // namespace vtloc::cli
