// Wavefront OBJ: `v x y z [w]` vertices and `f` polygons whose corners are
// `i`, `i/t`, `i//n` or `i/t/n` (1-based, or negative = relative to the last
// vertex read so far). Only positions are kept; every other statement
// (vt, vn, g, o, usemtl, mtllib, s, l, p, ...) is ignored.
#include <string>

#include "engine/io/file_bytes.h"
#include "engine/io/mesh_formats_detail.h"

namespace vtloc::io::detail {

TriangleMesh load_obj(const std::string& path, const std::vector<uint8_t>& bytes) {
    LineReader in(bytes, true);
    MeshBuilder mb(path, "line", 1);
    std::vector<std::string_view> w;
    std::vector<int64_t> idx;
    auto where = [&] { return "line " + std::to_string(in.line()); };
    while (in.next(w)) {
        if (w[0] == "v") {
            auto vname = [&] { return where() + " (vertex " + std::to_string(mb.vertex_count() + 1) + ")"; };
            if (w.size() < 4) fail(path, vname() + ": expected 'v x y z'");
            double xyz[3];
            for (int k = 0; k < 3; ++k)
                if (!parse_double(w[size_t(k) + 1], xyz[k]))
                    fail(path, vname() + ": '" + std::string(w[size_t(k) + 1]) + "' is not a number");
            mb.add_vertex(xyz, vname);
        } else if (w[0] == "f") {
            if (w.size() < 4) fail(path, where() + ": a face needs at least 3 vertices");
            idx.clear();
            for (size_t k = 1; k < w.size(); ++k) {
                std::string_view corner = w[k].substr(0, w[k].find('/'));
                int64_t i = 0;
                if (!parse_int(corner, i))
                    fail(path, where() + ": vertex reference '" + std::string(w[k]) + "' is not an integer index");
                if (i == 0) fail(path, where() + ": vertex index 0 (OBJ indices start at 1)");
                const int64_t seen = int64_t(mb.vertex_count());
                if (i < 0 && -i > seen)
                    fail(path, where() + ": relative vertex index " + std::to_string(i) + " out of range (" +
                                   std::to_string(seen) + " vertices so far)");
                // Positive indices may name vertices defined further down; the builder checks them at the end.
                idx.push_back(i < 0 ? seen + i : i - 1);
            }
            mb.add_polygon(idx.data(), idx.size(), in.line());
        }
    }
    return mb.finish();
}

}  // namespace vtloc::io::detail
