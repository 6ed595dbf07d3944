// Finding the shipped model and examples from any working directory.
#include "apps/vtloc/cli.h"

#ifndef VTLOC_SOURCE_DIR
#define VTLOC_SOURCE_DIR ""
#endif
#ifndef VTLOC_INSTALL_DATADIR
#define VTLOC_INSTALL_DATADIR "share/vtloc"
#endif

namespace vtloc::cli {

namespace fs = std::filesystem;

fs::path shipped_dir() {
    try {
        return find_shipped_dir(shipped_dir_candidates(current_executable(), VTLOC_INSTALL_DATADIR, VTLOC_SOURCE_DIR));
    } catch (const Error& e) {  // the CLI reports api::Error as a user's error
        throw api::Error(e.what());
    }
}

std::string default_model_path() { return (shipped_dir() / kDefaultModel).string(); }

// By name: a copy of the shipped random file is just as untrained.
bool is_shipped_random_model(const std::string& path) {
    return fs::path(path).filename() == fs::path(kRandomModel).filename();
}

}  // namespace vtloc::cli
