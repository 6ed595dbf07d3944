// The dataset readers of vtloc eval / vtloc synth: dataset.json, an object's
// object.json, points.csv and touches.csv. The input is those four files
// separated by lines "=====" (the seed corpus is a real one-object dataset).
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include "base/error.h"
#include "engine/sim/dataset.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    namespace fs = std::filesystem;
    static const fs::path root = "/dev/shm/vtloc-fuzz-dataset-" + std::to_string(getpid());
    static const char* const kFiles[] = {"dataset.json", "objects/o/object.json", "objects/o/points.csv",
                                         "objects/o/touches.csv"};
    fs::create_directories(root / "objects" / "o");
    const std::string in(reinterpret_cast<const char*>(data), size), sep = "\n=====\n";
    size_t at = 0;
    for (const char* name : kFiles) {
        const size_t end = std::min(in.find(sep, at), in.size());
        std::ofstream(root / name, std::ios::binary) << in.substr(std::min(at, in.size()), end - std::min(at, in.size()));
        at = end == in.size() ? in.size() : end + sep.size();
    }
    try {
        vtloc::sim::read_dataset(root.string());
    } catch (const vtloc::Error&) {
    }
    return 0;
}
