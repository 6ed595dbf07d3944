#include "engine/io/ply_header.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstring>
#include <string_view>
#include <utility>

#include "engine/io/file_bytes.h"
#include "engine/io/mesh_formats_detail.h"

namespace vtloc::io::ply {

namespace {

bool parse_type(std::string_view s, Type& t) {
    static const std::pair<std::string_view, Type> table[] = {
        {"char", Type::I8},   {"int8", Type::I8},    {"uchar", Type::U8},   {"uint8", Type::U8},
        {"short", Type::I16}, {"int16", Type::I16},  {"ushort", Type::U16}, {"uint16", Type::U16},
        {"int", Type::I32},   {"int32", Type::I32},  {"uint", Type::U32},   {"uint32", Type::U32},
        {"float", Type::F32}, {"float32", Type::F32}, {"double", Type::F64}, {"float64", Type::F64}};
    for (const auto& [name, type] : table)
        if (s == name) {
            t = type;
            return true;
        }
    return false;
}

}  // namespace

size_t type_size(Type t) {
    switch (t) {
        case Type::I8: case Type::U8: return 1;
        case Type::I16: case Type::U16: return 2;
        case Type::I32: case Type::U32: case Type::F32: return 4;
        case Type::F64: return 8;
    }
    return 0;
}

Header parse_header(const std::vector<uint8_t>& bytes, const std::string& path) {
    const std::string_view all(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    size_t pos = 0;
    bool have_format = false;
    Header h;
    std::vector<std::string_view> w;
    auto bad = [&](std::string_view line, const std::string& why) {
        fail(path, "malformed PLY header, line " + std::to_string(h.lines) + " '" + std::string(line) + "': " + why);
    };
    while (true) {
        if (pos >= all.size()) {
            if (h.lines == 0) fail(path, "not a PLY file (it is empty)");
            fail(path, "malformed PLY header: no end_header line");
        }
        size_t nl = all.find('\n', pos);
        if (nl == std::string_view::npos) nl = all.size();  // a last line without its newline
        std::string_view line = all.substr(pos, nl - pos);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        pos = std::min(nl + 1, all.size());
        ++h.lines;
        if (h.lines == 1) {
            if (line != "ply") fail(path, "not a PLY file (it does not start with a 'ply' line)");
            continue;
        }
        detail::split_tokens(line, w);
        if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
        if (w[0] == "end_header") break;
        if (w[0] == "format") {
            if (w.size() < 2) bad(line, "format without a name");
            if (w[1] == "ascii") h.encoding = Encoding::Ascii;
            else if (w[1] == "binary_little_endian") h.encoding = Encoding::Little;
            else if (w[1] == "binary_big_endian") h.encoding = Encoding::Big;
            else bad(line, "unknown format '" + std::string(w[1]) + "'");
            have_format = true;
        } else if (w[0] == "element") {
            if (w.size() != 3) bad(line, "expected 'element <name> <count>'");
            Elem e;
            e.name = std::string(w[1]);
            auto r = std::from_chars(w[2].data(), w[2].data() + w[2].size(), e.count);
            if (r.ec != std::errc() || r.ptr != w[2].data() + w[2].size() || e.count < 0)
                bad(line, "element count is not a non-negative integer");
            h.elems.push_back(std::move(e));
        } else if (w[0] == "property") {
            if (h.elems.empty()) bad(line, "property before any element");
            Prop p;
            if (w.size() == 5 && w[1] == "list") {
                p.list = true;
                if (!parse_type(w[2], p.count_type) || !parse_type(w[3], p.type)) bad(line, "unknown type in list property");
                if (p.count_type == Type::F32 || p.count_type == Type::F64) bad(line, "a list count must have an integer type");
            } else if (w.size() == 3) {
                if (!parse_type(w[1], p.type)) bad(line, "unknown type '" + std::string(w[1]) + "'");
            } else {
                bad(line, "expected 'property <type> <name>' or 'property list <count type> <type> <name>'");
            }
            p.name = std::string(w.back());
            h.elems.back().props.push_back(std::move(p));
        } else {
            bad(line, "unknown keyword '" + std::string(w[0]) + "'");
        }
    }
    if (!have_format) fail(path, "malformed PLY header: no format line");
    h.data_start = pos;
    return h;
}

double read_binary(const uint8_t* p, Type t, bool big_endian) {
    uint8_t b[8];
    const size_t n = type_size(t);
    std::memcpy(b, p, n);
    if (big_endian != (std::endian::native == std::endian::big))
        for (size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
    auto as = [&b]<class V>(V) {
        V v;
        std::memcpy(&v, b, sizeof v);
        return double(v);
    };
    switch (t) {
        case Type::I8: return as(int8_t());
        case Type::U8: return as(uint8_t());
        case Type::I16: return as(int16_t());
        case Type::U16: return as(uint16_t());
        case Type::I32: return as(int32_t());
        case Type::U32: return as(uint32_t());
        case Type::F32: return as(float());
        case Type::F64: return as(double());
    }
    return 0;
}

}  // namespace vtloc::io::ply
