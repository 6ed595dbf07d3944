#include "engine/io/candidates.h"

#include <cmath>

#include "engine/io/file_bytes.h"
#include "engine/io/ply.h"
#include "engine/io/point_text.h"

namespace vtloc::io {


HostTensor load_candidates(const std::string& path) {
    if (extension_of(path) != "ply") return load_point_text(path, "candidate points", false);
    HostTensor c = ply_columns(read_ply_vertices(path), {"x", "y", "z"}, path);
    if (c.shape[0] == 0) fail(path, "no candidate points in the file");
    for (int64_t i = 0; i < c.shape[0]; ++i)
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(c.data[size_t(i) * 3 + size_t(k)]))
                fail(path, "vertex " + std::to_string(i) + " has a non-finite coordinate");
    return c;
}

}  // namespace vtloc::io
