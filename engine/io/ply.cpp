#include "engine/io/ply.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <string_view>

#include "base/error.h"
#include "engine/io/file_bytes.h"
#include "engine/io/mesh_formats_detail.h"
#include "engine/io/ply_header.h"

namespace vtloc::io {

namespace {

// Binary data: walks the elements in order, keeping the vertex element's scalars.
void read_binary_data(const std::vector<uint8_t>& bytes, const ply::Header& h, PlyVertices& out, const std::string& path) {
    bool big = h.encoding == ply::Encoding::Big;
    size_t pos = h.data_start;
    for (const ply::Elem& e : h.elems) {
        bool is_vertex = e.name == "vertex";
        bool fixed = true;
        size_t row = 0;
        for (auto& p : e.props) {
            fixed = fixed && !p.list;
            row += ply::type_size(p.type);
        }
        auto truncated = [&](int64_t i) {
            fail(path, "truncated PLY data: element '" + e.name + "' ends after " + std::to_string(i) + " of " +
                           std::to_string(e.count) + " rows");
        };
        // Fixed-size rows: check the whole element fits before allocating for it.
        if (fixed && uint64_t(e.count) > (bytes.size() - pos) / std::max<size_t>(row, 1))
            truncated(int64_t((bytes.size() - pos) / std::max<size_t>(row, 1)));
        // (Bounded by the file size: a header may claim more rows than the data holds.)
        if (is_vertex) out.values.reserve(size_t(std::min<uint64_t>(uint64_t(e.count), bytes.size())) * out.names.size());
        for (int64_t i = 0; i < e.count; ++i) {
            for (auto& p : e.props) {
                if (p.list) {
                    size_t cs = ply::type_size(p.count_type);
                    if (bytes.size() - pos < cs) truncated(i);
                    double n = ply::read_binary(&bytes[pos], p.count_type, big);
                    pos += cs;
                    if (n < 0) fail(path, "element '" + e.name + "' row " + std::to_string(i) + ": negative list length");
                    size_t skip = size_t(n) * ply::type_size(p.type);
                    if (bytes.size() - pos < skip) truncated(i);
                    pos += skip;
                } else {
                    size_t n = ply::type_size(p.type);
                    if (bytes.size() - pos < n) truncated(i);
                    if (is_vertex) out.values.push_back(ply::read_binary(&bytes[pos], p.type, big));
                    pos += n;
                }
            }
        }
        if (is_vertex) return;
    }
}

// Ascii data: one element row per line (blank lines tolerated), values
// separated by white space.
void read_ascii_data(const std::vector<uint8_t>& bytes, const ply::Header& h, PlyVertices& out, const std::string& path,
                     int64_t header_lines) {
    std::string_view all(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    size_t pos = h.data_start;
    int64_t line_no = header_lines;
    for (const ply::Elem& e : h.elems) {
        bool is_vertex = e.name == "vertex";
        for (int64_t i = 0; i < e.count; ++i) {
            std::vector<std::string_view> w;
            while (w.empty()) {
                if (pos >= all.size())
                    fail(path, "truncated PLY data: element '" + e.name + "' ends after " + std::to_string(i) +
                                   " of " + std::to_string(e.count) + " rows");
                size_t nl = all.find('\n', pos);
                if (nl == std::string_view::npos) nl = all.size();
                detail::split_tokens(all.substr(pos, nl - pos), w);
                pos = nl + 1;
                ++line_no;
            }
            auto where = [&] { return "line " + std::to_string(line_no) + " (" + e.name + " " + std::to_string(i) + ")"; };
            size_t k = 0;
            auto next = [&]() -> double {
                if (k >= w.size()) fail(path, where() + ": too few values");
                std::string_view t = w[k++];
                if (t.size() > 1 && t[0] == '+') t.remove_prefix(1);  // from_chars rejects a leading '+'
                double v = 0;
                auto r = std::from_chars(t.data(), t.data() + t.size(), v);
                if (r.ec == std::errc::result_out_of_range) fail(path, where() + ": value '" + std::string(t) + "' out of range");
                if (r.ec != std::errc() || r.ptr != t.data() + t.size())
                    fail(path, where() + ": '" + std::string(t) + "' is not a number");
                return v;
            };
            for (auto& p : e.props) {
                if (p.list) {
                    double n = next();
                    if (n < 0 || n != double(int64_t(n))) fail(path, where() + ": bad list length");
                    for (int64_t j = 0; j < int64_t(n); ++j) next();
                } else {
                    double v = next();
                    if (is_vertex) out.values.push_back(v);
                }
            }
            if (k != w.size()) fail(path, where() + ": too many values");
        }
        if (is_vertex) return;
    }
}

// std::to_chars gives the shortest text that reads back to the same float, in
// the "C" locale whatever the process locale is.
void append_float(std::string& s, float v) {
    char buf[32];
    auto r = std::to_chars(buf, buf + sizeof buf, v);
    s.append(buf, r.ptr);
}

}  // namespace

int PlyVertices::column(const std::string& name) const {
    for (size_t i = 0; i < names.size(); ++i)
        if (names[i] == name) return int(i);
    return -1;
}

PlyVertices read_ply_vertices(const std::string& path) {
    std::vector<uint8_t> bytes = read_file_bytes(path);
    if (bytes.empty()) fail(path, "file is empty, not a PLY file");
    const ply::Header h = ply::parse_header(bytes, path);
    const ply::Elem* vertex = nullptr;
    for (auto& e : h.elems)
        if (e.name == "vertex") {
            vertex = &e;
            break;
        }
    if (!vertex) fail(path, "PLY file has no vertex element");
    PlyVertices out;
    out.count = vertex->count;
    for (auto& e : h.elems) out.elements.push_back(e.name);
    for (auto& p : vertex->props)
        if (!p.list && out.column(p.name) < 0) out.names.push_back(p.name);
    if (out.names.size() != [&] {
            size_t n = 0;
            for (auto& p : vertex->props) n += !p.list;
            return n;
        }())
        fail(path, "malformed PLY header: a vertex property name appears twice");
    if (h.encoding == ply::Encoding::Ascii) {
        read_ascii_data(bytes, h, out, path, h.lines);
    } else {
        read_binary_data(bytes, h, out, path);
    }
    return out;
}

HostTensor ply_columns(const PlyVertices& v, const std::vector<std::string>& names, const std::string& path) {
    std::vector<int> cols;
    for (auto& n : names) {
        int c = v.column(n);
        if (c < 0) fail(path, "PLY vertices have no property '" + n + "'");
        cols.push_back(c);
    }
    HostTensor t({v.count, int64_t(names.size())});
    size_t width = v.names.size();
    for (int64_t i = 0; i < v.count; ++i)
        for (size_t j = 0; j < cols.size(); ++j)
            t.data[size_t(i) * cols.size() + j] = float(v.values[size_t(i) * width + size_t(cols[j])]);
    return t;
}

void write_ply(const std::string& path, const HostTensor& points, const PlyWriteOptions& o) {
    if (points.shape.size() != 2 || (points.shape[1] != 3 && points.shape[1] != 6))
        throw Error("write_ply(" + path + "): points must be N x 3 or N x 6, got " + shape_str(points.shape));
    const size_t n = size_t(points.shape[0]), d = size_t(points.shape[1]);
    if (!o.contact_prob.empty() && o.contact_prob.size() != n)
        throw Error("write_ply(" + path + "): " + std::to_string(o.contact_prob.size()) + " probabilities for " +
                    std::to_string(n) + " points");
    if (!o.rgb.empty() && o.rgb.size() != 3 * n)
        throw Error("write_ply(" + path + "): colours must be 3 per point");
    static const char* kNames[] = {"x", "y", "z", "nx", "ny", "nz"};
    std::string s = "ply\nformat ";
    s += o.format == PlyFormat::Ascii ? "ascii 1.0\n" : "binary_little_endian 1.0\n";
    for (auto& c : o.comments) s += "comment " + c + "\n";
    s += "element vertex " + std::to_string(n) + "\n";
    for (size_t j = 0; j < d; ++j) s += std::string("property float ") + kNames[j] + "\n";
    if (!o.contact_prob.empty()) s += "property float contact_prob\n";
    if (!o.rgb.empty()) s += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    s += "end_header\n";
    for (size_t i = 0; i < n; ++i) {
        const float* row = &points.data[i * d];
        if (o.format == PlyFormat::Ascii) {
            for (size_t j = 0; j < d; ++j) {
                if (j) s += ' ';
                append_float(s, row[j]);
            }
            if (!o.contact_prob.empty()) {
                s += ' ';
                append_float(s, o.contact_prob[i]);
            }
            for (size_t c = 0; c < 3 && !o.rgb.empty(); ++c) s += ' ' + std::to_string(int(o.rgb[3 * i + c]));
            s += '\n';
        } else {
            // Little-endian floats: a byte copy on the little-endian hosts we build for.
            static_assert(std::endian::native == std::endian::little, "binary PLY writer assumes a little-endian host");
            s.append(reinterpret_cast<const char*>(row), d * 4);
            if (!o.contact_prob.empty()) s.append(reinterpret_cast<const char*>(&o.contact_prob[i]), 4);
            if (!o.rgb.empty()) s.append(reinterpret_cast<const char*>(&o.rgb[3 * i]), 3);
        }
    }
    write_file_atomic(path, s.data(), s.size());
}

}  // namespace vtloc::io
