#pragma once
// Shared by the per-format mesh readers (mesh_off/obj/ply_faces/stl.cpp):
// text scanning, number parsing, and the builder that validates vertices and
// polygons, fan-triangulates and drops degenerate triangles in one place so
// that every format gives the same errors and the same cleaning.
#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "engine/io/mesh.h"

namespace vtloc::io::detail {

// Lines of a text file, '#' comments stripped (OFF and OBJ), numbered from 1.
class LineReader {
public:
    LineReader(const std::vector<uint8_t>& bytes, bool hash_comments)
        : all_(reinterpret_cast<const char*>(bytes.data()), bytes.size()), comments_(hash_comments) {}
    // From byte `start`, the lines before it counted as `lines_before` (a PLY file's data after its header).
    LineReader(const std::vector<uint8_t>& bytes, bool hash_comments, size_t start, int64_t lines_before)
        : LineReader(bytes, hash_comments) {
        pos_ = std::min(start, all_.size()), line_ = lines_before;
    }
    // Next line's tokens that has any (blank and comment-only lines skipped);
    // false at the end of the file.
    bool next(std::vector<std::string_view>& tokens);
    int64_t line() const { return line_; }
    size_t offset() const { return pos_; }  // bytes consumed so far
    size_t size() const { return all_.size(); }

private:
    std::string_view all_;
    bool comments_;
    size_t pos_ = 0;
    int64_t line_ = 0;
};

void split_tokens(std::string_view line, std::vector<std::string_view>& out);

// Strict whole-token parses (a leading '+' allowed); false when the token is
// not entirely a number of that kind. A double too large parses as +-DBL_MAX,
// which the vertex check then reports as an absurd size.
bool parse_double(std::string_view t, double& v);
bool parse_int(std::string_view t, int64_t& v);

// Finite and within kMaxMeshCoordinate; check_coordinates throws naming
// `where` when not.
bool coordinates_ok(const double xyz[3]);
void check_coordinates(const std::string& path, const double xyz[3], const std::string& where);

class MeshBuilder {
public:
    // face_label names a polygon in errors: "line" (text formats) or "face";
    // index_base is added to indices shown in errors (1 for OBJ).
    MeshBuilder(const std::string& path, std::string face_label, int index_base = 0)
        : path_(path), label_(std::move(face_label)), base_(index_base) {}

    // where() names the vertex in errors (e.g. "line 7 (vertex 3)"); it is
    // only called on failure, so the common path builds no strings.
    template <class Where>
    void add_vertex(const double xyz[3], Where&& where) {
        if (!coordinates_ok(xyz)) check_coordinates(path_, xyz, where());
        add_vertex_unchecked(float(xyz[0]), float(xyz[1]), float(xyz[2]));
    }
    void add_vertex_unchecked(float x, float y, float z);  // coordinates checked by the caller
    size_t vertex_count() const { return positions_.size() / 3; }

    // A polygon of zero-based indices, checked against the final vertex count
    // in finish() (OBJ and PLY may name vertices before they are read); tag
    // is its line or face number for errors.
    void add_polygon(const int64_t* idx, size_t n, int64_t tag);
    size_t polygon_count() const { return sizes_.size(); }

    // Range checks, fan triangulation, degenerate triangles dropped; throws
    // "no faces" / "only degenerate triangles" when nothing is left.
    TriangleMesh finish();

private:
    const std::string& path_;
    std::string label_;
    int base_;
    std::vector<float> positions_;
    std::vector<int64_t> indices_;
    std::vector<uint32_t> sizes_;
    std::vector<int64_t> tags_;
};

// Drops triangles with a repeated index or zero area (in place); returns how many.
size_t drop_degenerate(TriangleMesh& mesh);

TriangleMesh load_off(const std::string& path, const std::vector<uint8_t>& bytes);
TriangleMesh load_obj(const std::string& path, const std::vector<uint8_t>& bytes);
TriangleMesh load_ply_mesh(const std::string& path, const std::vector<uint8_t>& bytes);
TriangleMesh load_stl(const std::string& path, const std::vector<uint8_t>& bytes);

}  // namespace vtloc::io::detail
