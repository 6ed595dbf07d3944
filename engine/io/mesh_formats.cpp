// Mesh loading by extension, the validation and cleaning every format shares,
// and the binary PLY mesh writer. The per-format parsers live in
// mesh_off.cpp, mesh_obj.cpp, mesh_ply_faces.cpp and mesh_stl.cpp.
#include "engine/io/mesh_formats.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>

#include "base/error.h"
#include "engine/io/file_bytes.h"
#include "engine/io/mesh_formats_detail.h"

namespace vtloc::io {

namespace detail {

void split_tokens(std::string_view line, std::vector<std::string_view>& out) {
    out.clear();
    auto space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; };
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && space(line[i])) ++i;
        size_t j = i;
        while (j < line.size() && !space(line[j])) ++j;
        if (j > i) out.push_back(line.substr(i, j - i));
        i = j;
    }
}

bool LineReader::next(std::vector<std::string_view>& tokens) {
    while (pos_ < all_.size()) {
        size_t nl = all_.find('\n', pos_);
        if (nl == std::string_view::npos) nl = all_.size();
        std::string_view line = all_.substr(pos_, nl - pos_);
        pos_ = nl + 1;
        ++line_;
        if (comments_) line = line.substr(0, line.find('#'));
        split_tokens(line, tokens);
        if (!tokens.empty()) return true;
    }
    pos_ = all_.size();
    return false;
}

bool parse_double(std::string_view t, double& v) {
    if (t.size() > 1 && t[0] == '+') t.remove_prefix(1);  // from_chars rejects a leading '+'
    auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || r.ptr != t.data() + t.size()) return false;
    if (r.ec == std::errc()) return true;
    if (r.ec != std::errc::result_out_of_range) return false;
    // Out of range: overflow reads as +-DBL_MAX (reported later as an absurd
    // size, not as a NaN/inf the file did not write), underflow as zero.
    // Which one follows from the decimal magnitude of the leading significant
    // digit plus the exponent.
    std::string_view mant = t.substr(0, t.find_first_of("eE"));
    int64_t exp = 0;
    if (mant.size() < t.size() && !parse_int(t.substr(mant.size() + 1), exp))
        exp = t[mant.size() + 1] == '-' ? INT32_MIN : INT32_MAX;  // exponent too long for int64
    bool neg = !mant.empty() && mant[0] == '-';
    if (neg) mant.remove_prefix(1);
    size_t dot = std::min(mant.find('.'), mant.size());
    size_t first = mant.find_first_not_of("0.");
    if (first == std::string_view::npos) {
        v = 0;
        return true;
    }
    int64_t mag = first < dot ? int64_t(dot - first) - 1 : -int64_t(first - dot);
    const bool overflow = mag + std::clamp<int64_t>(exp, INT32_MIN, INT32_MAX) > 0;
    v = (overflow ? std::numeric_limits<double>::max() : 0.0) * (neg ? -1.0 : 1.0);
    return true;
}

bool parse_int(std::string_view t, int64_t& v) {
    if (t.size() > 1 && t[0] == '+') t.remove_prefix(1);
    auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    return r.ec == std::errc() && r.ptr == t.data() + t.size() && !t.empty();
}

bool coordinates_ok(const double xyz[3]) {
    for (int k = 0; k < 3; ++k)
        if (!(std::abs(xyz[k]) <= kMaxMeshCoordinate)) return false;  // NaN fails too
    return true;
}

void check_coordinates(const std::string& path, const double xyz[3], const std::string& where) {
    for (int k = 0; k < 3; ++k) {
        char buf[40], limit[40];
        std::snprintf(buf, sizeof buf, "%g", xyz[k]);
        std::snprintf(limit, sizeof limit, "%g", kMaxMeshCoordinate);
        if (!std::isfinite(xyz[k])) fail(path, where + ": coordinate " + buf + " is not finite (NaN/inf)");
        if (std::abs(xyz[k]) > kMaxMeshCoordinate)
            fail(path, where + ": coordinate " + buf + " is beyond +-" + limit + " (absurd size)");
    }
}

void MeshBuilder::add_vertex_unchecked(float x, float y, float z) {
    // Triangles hold uint32 indices.
    if (vertex_count() >= UINT32_MAX) fail(path_, "more than 2^32 - 1 vertices");
    positions_.insert(positions_.end(), {x, y, z});
}

void MeshBuilder::add_polygon(const int64_t* idx, size_t n, int64_t tag) {
    indices_.insert(indices_.end(), idx, idx + n);
    sizes_.push_back(uint32_t(n));
    tags_.push_back(tag);
}

TriangleMesh MeshBuilder::finish() {
    if (sizes_.empty()) fail(path_, "no faces (the mesh has no polygons)");
    const int64_t nv = int64_t(vertex_count());
    TriangleMesh m;
    size_t at = 0;
    for (size_t f = 0; f < sizes_.size(); ++f) {
        const int64_t* p = &indices_[at];
        for (uint32_t k = 0; k < sizes_[f]; ++k)
            if (p[k] < 0 || p[k] >= nv)
                fail(path_, label_ + " " + std::to_string(tags_[f]) + ": vertex index " + std::to_string(p[k] + base_) +
                                " out of range (" + std::to_string(nv) + " vertices)");
        // Fan (p0, pk, pk+1): exact for the convex polygons these formats store.
        for (uint32_t k = 1; k + 1 < sizes_[f]; ++k)
            m.triangles.insert(m.triangles.end(), {uint32_t(p[0]), uint32_t(p[k]), uint32_t(p[k + 1])});
        at += sizes_[f];
    }
    m.positions = std::move(positions_);
    size_t dropped = drop_degenerate(m);
    if (m.triangles.empty())
        fail(path_, "only degenerate triangles (all " + std::to_string(dropped) + " have zero area or a repeated vertex)");
    return m;
}

size_t drop_degenerate(TriangleMesh& m) {
    size_t kept = 0;
    const size_t nt = m.triangle_count();
    for (size_t t = 0; t < nt; ++t) {
        uint32_t a = m.triangles[3 * t], b = m.triangles[3 * t + 1], c = m.triangles[3 * t + 2];
        if (a == b || b == c || a == c) continue;
        // Double products of float differences: exact enough that only truly flat triangles give zero.
        double u[3], v[3];
        for (int k = 0; k < 3; ++k) {
            u[k] = double(m.positions[3 * size_t(b) + k]) - m.positions[3 * size_t(a) + k];
            v[k] = double(m.positions[3 * size_t(c) + k]) - m.positions[3 * size_t(a) + k];
        }
        double cx = u[1] * v[2] - u[2] * v[1], cy = u[2] * v[0] - u[0] * v[2], cz = u[0] * v[1] - u[1] * v[0];
        if (cx == 0 && cy == 0 && cz == 0) continue;
        m.triangles[3 * kept] = a;
        m.triangles[3 * kept + 1] = b;
        m.triangles[3 * kept + 2] = c;
        ++kept;
    }
    m.triangles.resize(3 * kept);
    return nt - kept;
}

}  // namespace detail

namespace {

// glTF comes through tinygltf already validated for ranges and finiteness; it
// still gets the size check and the same degenerate-triangle cleaning.
TriangleMesh load_gltf_cleaned(const std::string& path) {
    TriangleMesh m = load_gltf_mesh(path);
    for (size_t i = 0; i < m.vertex_count(); ++i) {
        const double xyz[3] = {m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]};
        if (!detail::coordinates_ok(xyz)) detail::check_coordinates(path, xyz, "vertex " + std::to_string(i));
    }
    size_t dropped = detail::drop_degenerate(m);
    if (m.triangles.empty())
        fail(path, "only degenerate triangles (all " + std::to_string(dropped) + " have zero area or a repeated vertex)");
    return m;
}

}  // namespace

TriangleMesh load_mesh(const std::string& path) {
    const std::string ext = extension_of(path);
    if (ext == "gltf" || ext == "glb") return load_gltf_cleaned(path);
    TriangleMesh (*reader)(const std::string&, const std::vector<uint8_t>&) = nullptr;
    if (ext == "off") reader = detail::load_off;
    else if (ext == "obj") reader = detail::load_obj;
    else if (ext == "ply") reader = detail::load_ply_mesh;
    else if (ext == "stl") reader = detail::load_stl;
    else
        fail(path, (ext.empty() ? std::string("no file extension") : "unknown mesh extension '." + ext + "'") +
                       " (supported: .off .obj .ply .stl .gltf .glb)");
    std::vector<uint8_t> bytes = read_file_bytes(path);
    if (bytes.empty()) fail(path, "file is empty");
    return reader(path, bytes);
}

void save_mesh_ply(const std::string& path, const TriangleMesh& mesh) {
    auto bad = [&](const std::string& why) { throw Error("save_mesh_ply(" + path + "): " + why); };
    if (mesh.positions.size() % 3 || mesh.triangles.size() % 3) bad("positions and triangles must come in threes");
    const size_t nv = mesh.vertex_count(), nt = mesh.triangle_count();
    // The face list stores int indices.
    if (nv > size_t(INT32_MAX)) bad("too many vertices for int indices");
    for (float c : mesh.positions)
        if (!std::isfinite(c)) bad("a vertex has a non-finite coordinate");
    for (uint32_t id : mesh.triangles)
        if (id >= nv) bad("triangle index " + std::to_string(id) + " out of range (" + std::to_string(nv) + " vertices)");
    static_assert(std::endian::native == std::endian::little, "binary PLY writer assumes a little-endian host");
    std::string s = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(nv) +
                    "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(nt) +
                    "\nproperty list uchar int vertex_indices\nend_header\n";
    const size_t header = s.size();
    s.resize(header + nv * 12 + nt * 13);
    char* p = s.data() + header;
    if (nv) std::memcpy(p, mesh.positions.data(), nv * 12);
    p += nv * 12;
    for (size_t t = 0; t < nt; ++t) {
        *p++ = 3;
        std::memcpy(p, &mesh.triangles[3 * t], 12);  // uint32 < 2^31 has the same bytes as int
        p += 12;
    }
    // Written aside, then renamed: a reader never sees half a file.
    const std::string tmp = path + ".tmp";
    write_file_bytes(tmp, s.data(), s.size());
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        std::filesystem::remove(tmp, ec);
        fail(path, "cannot be written (rename from " + tmp + " failed)");
    }
}

}  // namespace vtloc::io
