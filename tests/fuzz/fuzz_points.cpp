// The point-cloud readers (PLY vertices with or without normals, PCD ASCII and
// binary, XYZ/CSV text) and the cloud checks behind load_object.
#include "base/error.h"
#include "engine/io/object.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    static const char* const kExt[] = {".ply", ".pcd", ".xyz", ".csv"};
    const std::string path = vtloc::fuzz::write_input(data + 1, size - 1, kExt[data[0] % 4]);
    try {
        vtloc::io::load_object(path, 64);
    } catch (const vtloc::Error&) {
    }
    return 0;
}
