// OFF (Geomview Object File Format), read line by line: an optional
// [ST][C][N]OFF keyword (counts may follow on the same line), a
// "vertices faces [edges]" line, one vertex per line (x y z first; normals,
// colours and texture coordinates after them ignored), then one polygon per
// line ("n i0 .. in-1", a face colour after it ignored).
#include <algorithm>
#include <string>

#include "engine/io/file_bytes.h"
#include "engine/io/mesh_formats_detail.h"

namespace vtloc::io::detail {

namespace {

// True for OFF, COFF, NOFF, CNOFF, STOFF, STCNOFF, ...; the 4D and nD
// variants are reported as unsupported by the caller.
bool is_off_keyword(std::string_view w) {
    if (w.size() < 3 || w.substr(w.size() - 3) != "OFF") return false;
    std::string_view prefix = w.substr(0, w.size() - 3);
    if (prefix.substr(0, 2) == "ST") prefix.remove_prefix(2);
    if (!prefix.empty() && prefix[0] == 'C') prefix.remove_prefix(1);
    if (!prefix.empty() && prefix[0] == 'N') prefix.remove_prefix(1);
    return prefix.empty();
}

}  // namespace

TriangleMesh load_off(const std::string& path, const std::vector<uint8_t>& bytes) {
    LineReader in(bytes, true);
    std::vector<std::string_view> w;
    auto where = [&] { return "line " + std::to_string(in.line()); };
    if (!in.next(w)) fail(path, "malformed OFF header: the file has no content");
    size_t first_count = 0;  // index of the first count token on the header line
    if (is_off_keyword(w[0])) {
        first_count = 1;
    } else if (w[0].find("OFF") != std::string_view::npos) {
        fail(path, "unsupported OFF variant '" + std::string(w[0]) + "' (only 3D OFF, COFF, NOFF, STOFF)");
    } else {
        int64_t probe;
        if (!parse_int(w[0], probe)) fail(path, "not an OFF file (line 1 starts with '" + std::string(w[0]) + "')");
    }
    if (first_count == w.size()) {  // counts on a line of their own
        if (!in.next(w)) fail(path, "malformed OFF header: no vertex/face count line");
        first_count = 0;
    }
    int64_t nv = -1, nf = -1;
    if (w.size() - first_count < 2 || w.size() - first_count > 3 || !parse_int(w[first_count], nv) ||
        !parse_int(w[first_count + 1], nf) || nv < 0 || nf < 0)
        fail(path, "malformed OFF header, " + where() + ": expected 'vertices faces [edges]' as non-negative integers");
    // Fail fast on absurd counts: a vertex line takes at least 6 bytes ("0 0 0\n"),
    // a face line at least 8 ("3 0 1 2\n"); nothing is allocated from the counts.
    const uint64_t rest = in.size() - std::min(in.offset(), in.size()) + 1;
    if (uint64_t(nv) > rest / 6 || uint64_t(nf) > rest / 8)
        fail(path, "OFF header claims " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                       " faces but only " + std::to_string(rest - 1) + " bytes follow (truncated, or absurd counts)");

    MeshBuilder mb(path, "line");
    for (int64_t i = 0; i < nv; ++i) {
        if (!in.next(w))
            fail(path, "truncated OFF: the file ends after " + std::to_string(i) + " of " + std::to_string(nv) + " vertices");
        auto vname = [&] { return where() + " (vertex " + std::to_string(i) + ")"; };
        double xyz[3];
        if (w.size() < 3) fail(path, vname() + ": expected x y z");
        for (int k = 0; k < 3; ++k)
            if (!parse_double(w[size_t(k)], xyz[k]))
                fail(path, vname() + ": '" + std::string(w[size_t(k)]) + "' is not a number");
        mb.add_vertex(xyz, vname);
    }
    std::vector<int64_t> idx;
    for (int64_t f = 0; f < nf; ++f) {
        if (!in.next(w))
            fail(path, "truncated OFF: the file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces");
        auto fname = [&] { return where() + " (face " + std::to_string(f) + ")"; };
        int64_t n = 0;
        if (!parse_int(w[0], n) || n < 3) fail(path, fname() + ": expected a vertex count of at least 3, got '" + std::string(w[0]) + "'");
        if (uint64_t(n) > w.size() - 1)
            fail(path, fname() + ": " + std::to_string(n) + " vertices announced, " + std::to_string(w.size() - 1) + " values given");
        idx.resize(size_t(n));
        for (size_t k = 0; k < size_t(n); ++k)
            if (!parse_int(w[k + 1], idx[k]))
                fail(path, fname() + ": vertex index '" + std::string(w[k + 1]) + "' is not an integer");
        mb.add_polygon(idx.data(), idx.size(), in.line());
    }
    return mb.finish();
}

}  // namespace vtloc::io::detail
