// STL, binary or ASCII. Binary is recognised by its size (84 + 50 n bytes for
// the n triangles its header counts), not by the first word: binary files
// often begin with "solid" too. STL stores every triangle's corners
// separately, so equal corners are welded into one vertex (exact equality).
#include <bit>
#include <cctype>
#include <cstring>
#include <string>
#include <unordered_map>

#include "engine/io/file_bytes.h"
#include "engine/io/mesh_formats_detail.h"

namespace vtloc::io::detail {

namespace {

struct Key {
    uint32_t bits[3];
    bool operator==(const Key& o) const { return std::memcmp(bits, o.bits, sizeof bits) == 0; }
};
struct KeyHash {
    size_t operator()(const Key& k) const {
        uint64_t h = 0x9E3779B97F4A7C15ull;
        for (uint32_t b : k.bits) h = (h ^ b) * 0xBF58476D1CE4E5B9ull;
        return size_t(h ^ (h >> 31));
    }
};

class Welder {
public:
    Welder(const std::string& path, MeshBuilder& mb) : path_(path), mb_(mb) {}

    // Index of the vertex at xyz, added on first sight; where() names the corner in errors.
    template <class Where>
    int64_t corner(const double xyz[3], Where&& where) {
        if (!coordinates_ok(xyz)) check_coordinates(path_, xyz, where());
        Key k;
        for (int i = 0; i < 3; ++i) {
            float f = float(xyz[i]) + 0.0f;  // -0 becomes +0: they are equal, so they weld
            std::memcpy(&k.bits[i], &f, 4);
        }
        auto [it, added] = map_.try_emplace(k, int64_t(mb_.vertex_count()));
        if (added) {
            float f[3];
            std::memcpy(f, k.bits, sizeof f);
            mb_.add_vertex_unchecked(f[0], f[1], f[2]);
        }
        return it->second;
    }

private:
    const std::string& path_;
    MeshBuilder& mb_;
    std::unordered_map<Key, int64_t, KeyHash> map_;
};

TriangleMesh load_binary(const std::string& path, const std::vector<uint8_t>& bytes, uint64_t n) {
    MeshBuilder mb(path, "triangle");
    Welder weld(path, mb);
    for (uint64_t t = 0; t < n; ++t) {
        const uint8_t* rec = &bytes[84 + 50 * t];
        int64_t idx[3];
        for (int c = 0; c < 3; ++c) {
            float f[3];
            std::memcpy(f, rec + 12 + 12 * c, 12);  // after the facet normal, which is ignored
            const double xyz[3] = {f[0], f[1], f[2]};
            idx[c] = weld.corner(xyz, [&] { return "triangle " + std::to_string(t) + " vertex " + std::to_string(c); });
        }
        mb.add_polygon(idx, 3, int64_t(t));
    }
    return mb.finish();
}

// solid / facet normal / outer loop / vertex x y z (3 or more) / endloop /
// endfacet / endsolid; a loop of more than 3 vertices is fan-triangulated.
TriangleMesh load_ascii(const std::string& path, const std::vector<uint8_t>& bytes) {
    LineReader in(bytes, false);
    MeshBuilder mb(path, "line");
    Welder weld(path, mb);
    std::vector<std::string_view> w;
    std::vector<int64_t> loop;
    enum { Outside, InSolid, InFacet, InLoop } state = Outside;
    auto where = [&] { return "line " + std::to_string(in.line()); };
    auto expect = [&](bool ok, const char* what) {
        if (!ok) fail(path, where() + ": expected " + what + ", found '" + std::string(w[0]) + "'");
    };
    while (in.next(w)) {
        const std::string_view k = w[0];
        switch (state) {
            case Outside:
                expect(k == "solid", "'solid'");
                state = InSolid;
                break;
            case InSolid:
                if (k == "endsolid") {
                    state = Outside;
                } else {
                    expect(k == "facet", "'facet' or 'endsolid'");
                    state = InFacet;
                }
                break;
            case InFacet:
                if (k == "endfacet") {
                    state = InSolid;
                } else {
                    expect(k == "outer" && w.size() == 2 && w[1] == "loop", "'outer loop' or 'endfacet'");
                    state = InLoop;
                    loop.clear();
                }
                break;
            case InLoop:
                if (k == "vertex") {
                    double xyz[3];
                    if (w.size() != 4) fail(path, where() + ": expected 'vertex x y z'");
                    for (int c = 0; c < 3; ++c)
                        if (!parse_double(w[size_t(c) + 1], xyz[c]))
                            fail(path, where() + ": '" + std::string(w[size_t(c) + 1]) + "' is not a number");
                    loop.push_back(weld.corner(xyz, [&] { return where() + " (vertex)"; }));
                } else {
                    expect(k == "endloop", "'vertex' or 'endloop'");
                    if (loop.size() < 3) fail(path, where() + ": a facet needs at least 3 vertices, this one has " + std::to_string(loop.size()));
                    mb.add_polygon(loop.data(), loop.size(), in.line());
                    state = InFacet;
                }
                break;
        }
    }
    // Tolerated: a missing final endsolid. Not: a file that stops inside a facet.
    if (state == InFacet || state == InLoop) fail(path, "truncated ASCII STL: the file ends inside a facet");
    return mb.finish();
}

}  // namespace

TriangleMesh load_stl(const std::string& path, const std::vector<uint8_t>& bytes) {
    static_assert(std::endian::native == std::endian::little, "binary STL reader assumes a little-endian host");
    uint32_t n = 0;
    if (bytes.size() >= 84) std::memcpy(&n, &bytes[80], 4);  // little-endian count, on little-endian hosts
    if (bytes.size() >= 84 && bytes.size() == 84 + 50 * uint64_t(n)) return load_binary(path, bytes, n);
    size_t first = 0;
    while (first < bytes.size() && std::isspace(bytes[first])) ++first;
    if (bytes.size() - first >= 5 && std::memcmp(&bytes[first], "solid", 5) == 0) return load_ascii(path, bytes);
    if (bytes.size() < 84) fail(path, "not an STL file: too short for a binary STL (84-byte header) and not ASCII");
    fail(path, "truncated binary STL: its header counts " + std::to_string(n) + " triangles (" +
                   std::to_string(84 + 50 * uint64_t(n)) + " bytes) but the file has " + std::to_string(bytes.size()) +
                   " bytes");
}

}  // namespace vtloc::io::detail
