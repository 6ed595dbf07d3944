// PCD point clouds (PCL's format): the header, then ascii rows or packed
// binary records. See load_pcd in object.h for what is accepted.
#include <cmath>
#include <cstring>
#include <sstream>
#include <vector>

#include "engine/io/file_bytes.h"
#include "engine/io/object.h"

namespace vtloc::io {

namespace {

struct Field {
    std::string name;
    int size = 4;
    char type = 'F';
    int count = 1;
};

double read_binary(const uint8_t* p, const Field& f) {
    switch (f.type) {
        case 'F':
            if (f.size == 4) { float v; std::memcpy(&v, p, 4); return v; }
            if (f.size == 8) { double v; std::memcpy(&v, p, 8); return v; }
            break;
        case 'I':
            if (f.size == 1) return double(int8_t(p[0]));
            if (f.size == 2) { int16_t v; std::memcpy(&v, p, 2); return v; }
            if (f.size == 4) { int32_t v; std::memcpy(&v, p, 4); return v; }
            if (f.size == 8) { int64_t v; std::memcpy(&v, p, 8); return double(v); }
            break;
        case 'U':
            if (f.size == 1) return p[0];
            if (f.size == 2) { uint16_t v; std::memcpy(&v, p, 2); return v; }
            if (f.size == 4) { uint32_t v; std::memcpy(&v, p, 4); return v; }
            if (f.size == 8) { uint64_t v; std::memcpy(&v, p, 8); return double(v); }
            break;
    }
    return std::nan("");
}

struct Header {
    std::vector<Field> fields;
    int64_t points = -1;
    std::string data;  // the DATA keyword's value; empty until the DATA line
    size_t pos = 0;    // the first byte after the header
};

std::vector<int> header_ints(const std::string& path, const std::string& where, const char* what,
                             const std::vector<std::string>& vals, size_t fields) {
    if (vals.size() != fields) fail(path, where + ": " + what + " has " + std::to_string(vals.size()) +
                                              " values for " + std::to_string(fields) + " fields");
    std::vector<int> out;
    for (const auto& v : vals) {
        char* end = nullptr;
        const long x = std::strtol(v.c_str(), &end, 10);
        if (*end != 0 || x < 1 || x > 1 << 20) fail(path, where + ": bad " + what + " '" + v + "'");
        out.push_back(int(x));
    }
    return out;
}

void header_line(const std::string& path, const std::string& where, const std::string& key,
                 const std::vector<std::string>& vals, Header& h) {
    auto& fields = h.fields;
    if (key == "FIELDS") {
        for (const auto& v : vals) fields.push_back(Field{v});
    } else if (key == "SIZE") {
        auto s = header_ints(path, where, "SIZE", vals, fields.size());
        for (size_t i = 0; i < s.size(); ++i) fields[i].size = s[i];
    } else if (key == "COUNT") {
        auto c = header_ints(path, where, "COUNT", vals, fields.size());
        for (size_t i = 0; i < c.size(); ++i) fields[i].count = c[i];
    } else if (key == "TYPE") {
        if (vals.size() != fields.size()) fail(path, where + ": TYPE does not match FIELDS");
        for (size_t i = 0; i < vals.size(); ++i) {
            if (vals[i].size() != 1 || std::string("FIU").find(vals[i][0]) == std::string::npos)
                fail(path, where + ": unknown TYPE '" + vals[i] + "'");
            fields[i].type = vals[i][0];
        }
    } else if (key == "POINTS") {
        char* end = nullptr;
        h.points = vals.size() == 1 ? std::strtoll(vals[0].c_str(), &end, 10) : -1;
        if (vals.size() != 1 || *end != 0 || h.points < 0 || h.points > (int64_t(1) << 31))
            fail(path, where + ": bad POINTS");
    } else if (key == "DATA") {
        h.data = vals.empty() ? std::string("?") : vals[0];
    } else if (key != "VERSION" && key != "WIDTH" && key != "HEIGHT" && key != "VIEWPOINT") {
        fail(path, where + ": unknown keyword '" + key + "'");
    }
}

Header read_header(const std::string& path, const std::vector<uint8_t>& bytes) {
    Header h;
    size_t& pos = h.pos;
    int line_no = 0;
    while (h.data.empty()) {
        if (pos >= bytes.size()) fail(path, "the PCD header has no DATA line");
        size_t nl = pos;
        while (nl < bytes.size() && bytes[nl] != '\n') ++nl;
        std::string line(bytes.begin() + std::ptrdiff_t(pos), bytes.begin() + std::ptrdiff_t(nl));
        pos = nl < bytes.size() ? nl + 1 : nl;  // a last line without '\n' (the fuzzer's DATA line) ends the file
        ++line_no;
        if (line.empty() || line[0] == '#') continue;
        std::istringstream ss(line);
        std::string key;
        ss >> key;
        std::vector<std::string> vals;
        for (std::string v; ss >> v;) vals.push_back(v);
        header_line(path, "PCD header line " + std::to_string(line_no), key, vals, h);
        if (line_no > 64) fail(path, "not a PCD file (no DATA line in the first 64 lines)");
    }
    if (h.points < 0) fail(path, "the PCD header has no POINTS line");
    if (h.data != "ascii" && h.data != "binary")
        fail(path, "PCD DATA " + h.data + " is not supported (ascii or binary; save binary_compressed clouds as binary)");
    return h;
}

// Where each value of a record lies, and which values are x y z nx ny nz.
struct Layout {
    std::vector<int> col = std::vector<int>(6, -1);  // value offset of x y z nx ny nz in a record
    std::vector<int> value_at;                       // value index -> byte offset (binary)
    std::vector<const Field*> field_of;              // value index -> its field
    int values = 0, record = 0;
};

Layout record_layout(const std::string& path, const std::vector<Field>& fields) {
    Layout l;
    const char* names[6] = {"x", "y", "z", "normal_x", "normal_y", "normal_z"};
    for (const Field& f : fields) {
        if (f.type == 'F' && f.size != 4 && f.size != 8) fail(path, "PCD field " + f.name + ": float of size " + std::to_string(f.size));
        if (f.type != 'F' && f.size != 1 && f.size != 2 && f.size != 4 && f.size != 8)
            fail(path, "PCD field " + f.name + ": integer of size " + std::to_string(f.size));
        for (int k = 0; k < 6; ++k)
            if (f.name == names[k]) l.col[size_t(k)] = l.values;
        for (int c = 0; c < f.count; ++c) l.value_at.push_back(l.record + c * f.size);
        l.values += f.count;
        l.record += f.size * f.count;
    }
    for (const Field& f : fields)
        for (int c = 0; c < f.count; ++c) l.field_of.push_back(&f);
    if (l.col[0] < 0 || l.col[1] < 0 || l.col[2] < 0) fail(path, "the PCD file has no x y z fields");
    return l;
}

}  // namespace

HostTensor load_pcd(const std::string& path) {
    const std::vector<uint8_t> bytes = read_file_bytes(path);
    const Header h = read_header(path, bytes);
    const Layout l = record_layout(path, h.fields);
    const std::vector<int>& col = l.col;
    const int64_t points = h.points;
    const size_t pos = h.pos;
    const bool normals = col[3] >= 0 && col[4] >= 0 && col[5] >= 0;
    const int width = normals ? 6 : 3;
    std::vector<float> out;
    std::vector<double> row(static_cast<size_t>(l.values));
    auto keep = [&]() {  // a NaN coordinate is PCL's "no measurement"; the rest is load_object's check_cloud
        for (int k = 0; k < 3; ++k)
            if (std::isnan(row[size_t(col[size_t(k)])])) return;
        for (int k = 0; k < width; ++k) out.push_back(float(row[size_t(col[size_t(k)])]));
    };
    if (h.data == "binary") {
        if (bytes.size() - pos < uint64_t(points) * uint64_t(l.record))
            fail(path, "the PCD data ends before its " + std::to_string(points) + " points");
        for (int64_t i = 0; i < points; ++i) {
            const uint8_t* r = bytes.data() + pos + size_t(i) * size_t(l.record);
            for (int v = 0; v < l.values; ++v) row[size_t(v)] = read_binary(r + l.value_at[size_t(v)], *l.field_of[size_t(v)]);
            keep();
        }
    } else {
        std::string text(bytes.begin() + std::ptrdiff_t(pos), bytes.end());
        std::istringstream ss(text);
        for (int64_t i = 0; i < points; ++i) {
            for (int v = 0; v < l.values; ++v) {
                std::string tok;
                if (!(ss >> tok)) fail(path, "the PCD data ends before its " + std::to_string(points) + " points");
                char* end = nullptr;
                row[size_t(v)] = std::strtod(tok.c_str(), &end);
                if (*end != 0) fail(path, "point " + std::to_string(i) + ": '" + tok + "' is not a number");
            }
            keep();
        }
    }
    if (out.empty()) fail(path, "the PCD file has no point with measured (non-NaN) coordinates");
    const int64_t n = int64_t(out.size()) / width;
    return HostTensor({n, width}, std::move(out));
}

}  // namespace vtloc::io
