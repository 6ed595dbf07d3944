// The mesh readers (PLY with faces, OBJ, OFF, STL, glTF, GLB) and the surface
// sampling after them. The first byte picks the format; the rest is the file.
#include "base/error.h"
#include "engine/io/mesh.h"
#include "engine/io/mesh_formats.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    static const char* const kExt[] = {".ply", ".obj", ".off", ".stl", ".gltf", ".glb"};
    const std::string path = vtloc::fuzz::write_input(data + 1, size - 1, kExt[data[0] % 6]);
    try {
        const vtloc::io::TriangleMesh m = vtloc::io::load_mesh(path);
        vtloc::io::sample_surface(m, 64, 1, "fuzz");
    } catch (const vtloc::Error&) {
    }
    return 0;
}
