// PLY meshes: x y z of the vertex element and the vertex_indices (or
// vertex_index) list of the face element, in ascii, binary_little_endian or
// binary_big_endian, any scalar/list types; everything else is skipped.
// ply.cpp's header parser is private to its point-cloud reader (vertex
// element only, lists never kept), so the few lines of header parsing that a
// face reader needs live here.
#include <bit>
#include <cmath>
#include <cstring>
#include <string>

#include "engine/io/file_bytes.h"
#include "engine/io/mesh_formats_detail.h"

namespace vtloc::io::detail {

namespace {

enum class T { I8, U8, I16, U16, I32, U32, F32, F64 };

bool type_of(std::string_view s, T& t) {
    static const std::pair<std::string_view, T> table[] = {
        {"char", T::I8},   {"int8", T::I8},    {"uchar", T::U8},   {"uint8", T::U8},   {"short", T::I16},
        {"int16", T::I16}, {"ushort", T::U16}, {"uint16", T::U16}, {"int", T::I32},    {"int32", T::I32},
        {"uint", T::U32},  {"uint32", T::U32}, {"float", T::F32},  {"float32", T::F32}, {"double", T::F64},
        {"float64", T::F64}};
    for (auto& [name, type] : table)
        if (s == name) {
            t = type;
            return true;
        }
    return false;
}

size_t size_of(T t) { return t == T::I8 || t == T::U8 ? 1 : t == T::I16 || t == T::U16 ? 2 : t == T::F64 ? 8 : 4; }

struct Prop {
    std::string name;
    T type = T::F32;
    bool list = false;
    T count_type = T::U8;
};

struct Elem {
    std::string name;
    int64_t count = 0;
    std::vector<Prop> props;
};

enum class Format { Ascii, Little, Big };

struct Header {
    Format format = Format::Ascii;
    std::vector<Elem> elems;
};

Header parse_header(const std::string& path, LineReader& in) {
    Header h;
    std::vector<std::string_view> w;
    bool have_format = false;
    auto bad = [&](const std::string& why) {
        fail(path, "malformed PLY header, line " + std::to_string(in.line()) + ": " + why);
    };
    in.next(w);  // the "ply" line, checked by the caller
    while (true) {
        if (!in.next(w)) fail(path, "malformed PLY header: no end_header line");
        if (w[0] == "comment" || w[0] == "obj_info") continue;
        if (w[0] == "end_header") break;
        if (w[0] == "format") {
            if (w.size() != 3) bad("expected 'format <kind> 1.0'");
            if (w[1] == "ascii") h.format = Format::Ascii;
            else if (w[1] == "binary_little_endian") h.format = Format::Little;
            else if (w[1] == "binary_big_endian") h.format = Format::Big;
            else bad("unknown format '" + std::string(w[1]) + "'");
            have_format = true;
        } else if (w[0] == "element") {
            Elem e;
            if (w.size() != 3 || !parse_int(w[2], e.count) || e.count < 0)
                bad("expected 'element <name> <count>' with a non-negative integer count");
            e.name = std::string(w[1]);
            h.elems.push_back(std::move(e));
        } else if (w[0] == "property") {
            if (h.elems.empty()) bad("property before any element");
            Prop p;
            if (w.size() == 5 && w[1] == "list") {
                p.list = true;
                if (!type_of(w[2], p.count_type) || !type_of(w[3], p.type)) bad("unknown type in list property");
                if (p.count_type == T::F32 || p.count_type == T::F64) bad("a list count must have an integer type");
            } else if (w.size() != 3 || !type_of(w[1], p.type)) {
                bad("expected 'property <type> <name>' or 'property list <count type> <type> <name>'");
            }
            p.name = std::string(w.back());
            h.elems.back().props.push_back(std::move(p));
        } else {
            bad("unknown keyword '" + std::string(w[0]) + "'");
        }
    }
    if (!have_format) fail(path, "malformed PLY header: no format line");
    return h;
}

// Values of the data section in file order, ascii or binary, widened to
// double; every read is bounds-checked, so a truncated file fails, never overruns.
struct Reader {
    const std::string& path;
    const std::vector<uint8_t>& bytes;
    Format format;
    LineReader& text;
    size_t pos;  // binary read position
    std::vector<std::string_view> tokens;
    size_t next_token = 0;
    const Elem* elem = nullptr;
    int64_t row = 0;

    std::string where() const {
        std::string s = "element '" + elem->name + "' row " + std::to_string(row);
        return format == Format::Ascii ? "line " + std::to_string(text.line()) + " (" + s + ")" : s;
    }
    [[noreturn]] void truncated() const {
        fail(path, "truncated PLY data: the file ends in " + where() + " of " + std::to_string(elem->count));
    }

    double value(T t) {
        if (format == Format::Ascii) {
            while (next_token >= tokens.size()) {
                if (!text.next(tokens)) truncated();
                next_token = 0;
            }
            std::string_view tok = tokens[next_token++];
            double v = 0;
            if (!parse_double(tok, v)) fail(path, where() + ": '" + std::string(tok) + "' is not a number");
            return v;
        }
        const size_t n = size_of(t);
        if (bytes.size() - pos < n) truncated();
        uint8_t b[8];
        std::memcpy(b, &bytes[pos], n);
        pos += n;
        if ((format == Format::Big) != (std::endian::native == std::endian::big))
            for (size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
        auto as = [&b]<class V>(V) {
            V v;
            std::memcpy(&v, b, sizeof v);
            return double(v);
        };
        switch (t) {
            case T::I8: return as(int8_t());
            case T::U8: return as(uint8_t());
            case T::I16: return as(int16_t());
            case T::U16: return as(uint16_t());
            case T::I32: return as(int32_t());
            case T::U32: return as(uint32_t());
            case T::F32: return as(float());
            case T::F64: return as(double());
        }
        return 0;
    }

    // A list length or vertex index: a whole number (ascii text may say "3.0").
    int64_t integer(T t, const char* what) {
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
        if (format == Format::Ascii ? uint64_t(n) > bytes.size() : uint64_t(n) > (bytes.size() - pos) / size_of(p.type))
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
    std::string_view start(reinterpret_cast<const char*>(bytes.data()), std::min<size_t>(bytes.size(), 5));
    if (start.substr(0, 4) != "ply\n" && start != "ply\r\n") fail(path, "not a PLY file (it does not start with a 'ply' line)");
    LineReader text(bytes, false);
    const Header h = parse_header(path, text);

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
    const size_t data_start = std::min(text.offset(), bytes.size());
    const uint64_t rest = bytes.size() - data_start;
    uint64_t need = 0;
    for (auto& e : h.elems) {
        uint64_t min_row = 0;
        for (auto& p : e.props)
            min_row += h.format == Format::Ascii ? 2 : size_of(p.list ? p.count_type : p.type);
        if (min_row && uint64_t(e.count) > (rest + 1) / min_row)
            fail(path, "PLY header claims " + std::to_string(e.count) + " '" + e.name + "' rows but only " +
                           std::to_string(rest) + " bytes of data follow (truncated, or an absurd count)");
        need += uint64_t(e.count) * min_row;
        if (need > rest + 1)
            fail(path, "truncated PLY data: the header's counts need at least " + std::to_string(need) +
                           " bytes of data, the file has " + std::to_string(rest));
    }

    MeshBuilder mb(path, "face");
    Reader r{path, bytes, h.format, text, data_start, {}, 0, nullptr, 0};
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
                } else if (h.format != Format::Ascii) {
                    r.pos += size_t(n) * size_of(p.type);  // list_length checked that it fits
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
