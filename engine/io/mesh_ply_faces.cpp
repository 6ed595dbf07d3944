// PLY meshes: x y z of the vertex element and the vertex_indices (or
// vertex_index) list of the face element, in ascii, binary_little_endian or
// binary_big_endian, any scalar/list types; everything else is skipped. The
// header is ply_header.h's, as the point-cloud reader's.
#include <cmath>
#include <string>

#include "engine/io/file_bytes.h"
#include "engine/io/mesh_formats_detail.h"
#include "engine/io/ply_header.h"

namespace vtloc::io::detail {

namespace {

using ply::Type;
using ply::Prop;
using ply::Elem;
using ply::Encoding;

// Values of the data section in file order, ascii or binary, widened to
// double; every read is bounds-checked, so a truncated file fails, never overruns.
struct Reader {
    const std::string& path;
    const std::vector<uint8_t>& bytes;
    Encoding encoding;
    LineReader& text;
    size_t pos;  // binary read position
    std::vector<std::string_view> tokens;
    size_t next_token = 0;
    const Elem* elem = nullptr;
    int64_t row = 0;

    std::string where() const {
        std::string s = "element '" + elem->name + "' row " + std::to_string(row);
        return encoding == Encoding::Ascii ? "line " + std::to_string(text.line()) + " (" + s + ")" : s;
    }
    [[noreturn]] void truncated() const {
        fail(path, "truncated PLY data: the file ends in " + where() + " of " + std::to_string(elem->count));
    }

    double value(Type t) {
        if (encoding == Encoding::Ascii) {
            while (next_token >= tokens.size()) {
                if (!text.next(tokens)) truncated();
                next_token = 0;
            }
            std::string_view tok = tokens[next_token++];
            double v = 0;
            if (!parse_double(tok, v)) fail(path, where() + ": '" + std::string(tok) + "' is not a number");
            return v;
        }
        const size_t n = ply::type_size(t);
        if (bytes.size() - pos < n) truncated();
        pos += n;
        return ply::read_binary(&bytes[pos - n], t, encoding == Encoding::Big);
    }

    // A list length or vertex index: a whole number (ascii text may say "3.0").
    int64_t integer(Type t, const char* what) {
        double v = value(t);
        if (!(v == std::floor(v)) || std::abs(v) > 9e15)
            fail(path, where() + ": " + what + " " + std::to_string(v) + " is not an integer");
        return int64_t(v);
    }

    // A list's length, checked against the bytes left before anything is read for it.
    int64_t list_length(const Prop& p) {
        int64_t n = integer(p.count_type, "list length");
        if (n < 0) fail(path, where() + ": negative list length " + std::to_string(n));
        // Ascii values take at least a byte each: bounds what a face's index list may allocate.
        if (encoding == Encoding::Ascii ? uint64_t(n) > bytes.size() : uint64_t(n) > (bytes.size() - pos) / ply::type_size(p.type))
            truncated();
        return n;
    }
};

const Prop* find_prop(const Elem& e, std::string_view name, bool list) {
    for (auto& p : e.props)
        if (p.name == name && p.list == list) return &p;
    return nullptr;
}

}  // namespace

TriangleMesh load_ply_mesh(const std::string& path, const std::vector<uint8_t>& bytes) {
    const ply::Header h = ply::parse_header(bytes, path);
    LineReader text(bytes, false, h.data_start, h.lines);

    const Elem *vertex = nullptr, *face = nullptr;
    for (auto& e : h.elems) {
        if (e.name == "vertex" && !vertex) vertex = &e;
        if (e.name == "face" && !face) face = &e;
    }
    if (!vertex) fail(path, "PLY file has no vertex element");
    const Prop* xyz_props[3];
    for (int k = 0; k < 3; ++k) {
        const char* name[3] = {"x", "y", "z"};
        xyz_props[k] = find_prop(*vertex, name[k], false);
        if (!xyz_props[k]) fail(path, std::string("PLY vertex element has no scalar property '") + name[k] + "'");
    }
    if (!face || face->count == 0) fail(path, "no faces (the PLY file has no face element rows; a point cloud?)");
    const Prop* index_prop = find_prop(*face, "vertex_indices", true);
    if (!index_prop) index_prop = find_prop(*face, "vertex_index", true);
    if (!index_prop) fail(path, "PLY face element has no 'vertex_indices' (or 'vertex_index') list property");

    // Fail fast on counts the data cannot hold (a header may claim 10^12 rows):
    // each row takes at least its fixed-size parts in binary, or one
    // character and a separator per property in ascii.
    const size_t data_start = h.data_start;
    const uint64_t rest = bytes.size() - data_start;
    uint64_t need = 0;
    for (auto& e : h.elems) {
        uint64_t min_row = 0;
        for (auto& p : e.props)
            min_row += h.encoding == Encoding::Ascii ? 2 : ply::type_size(p.list ? p.count_type : p.type);
        if (min_row && uint64_t(e.count) > (rest + 1) / min_row)
            fail(path, "PLY header claims " + std::to_string(e.count) + " '" + e.name + "' rows but only " +
                           std::to_string(rest) + " bytes of data follow (truncated, or an absurd count)");
        need += uint64_t(e.count) * min_row;
        if (need > rest + 1)
            fail(path, "truncated PLY data: the header's counts need at least " + std::to_string(need) +
                           " bytes of data, the file has " + std::to_string(rest));
    }

    MeshBuilder mb(path, "face");
    Reader r{path, bytes, h.encoding, text, data_start, {}, 0, nullptr, 0};
    std::vector<int64_t> idx;
    for (const Elem& e : h.elems) {
        if (e.props.empty()) continue;  // rows of nothing: no data to step over
        r.elem = &e;
        const bool is_vertex = &e == vertex, is_face = &e == face;
        for (r.row = 0; r.row < e.count; ++r.row) {
            double xyz[3] = {0, 0, 0};
            for (const Prop& p : e.props) {
                if (!p.list) {
                    double v = r.value(p.type);
                    for (int k = 0; k < 3; ++k)
                        if (is_vertex && &p == xyz_props[k]) xyz[k] = v;
                    continue;
                }
                int64_t n = r.list_length(p);
                if (is_face && &p == index_prop) {
                    if (n < 3) fail(path, r.where() + ": a face needs at least 3 vertices, this one has " + std::to_string(n));
                    idx.resize(size_t(n));
                    for (auto& i : idx) i = r.integer(p.type, "vertex index");
                    mb.add_polygon(idx.data(), idx.size(), r.row);
                } else if (h.encoding != Encoding::Ascii) {
                    r.pos += size_t(n) * ply::type_size(p.type);  // list_length checked that it fits
                } else {
                    for (int64_t i = 0; i < n; ++i) r.value(p.type);
                }
            }
            if (is_vertex) mb.add_vertex(xyz, [&] { return "vertex " + std::to_string(r.row); });
        }
    }
    return mb.finish();
}

}  // namespace vtloc::io::detail
