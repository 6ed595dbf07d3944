#include "engine/io/point_text.h"

#include <charconv>
#include <cmath>
#include <string_view>
#include <vector>

#include "engine/io/file_bytes.h"

namespace vtloc::io {

namespace {

bool parse_number(std::string_view t, double& v) {
    if (t.size() > 1 && t[0] == '+') t.remove_prefix(1);
    auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    return r.ec == std::errc() && r.ptr == t.data() + t.size();
}

}  // namespace

HostTensor load_point_text(const std::string& path, const std::string& what, bool keep_normals) {
    std::vector<uint8_t> bytes = read_file_bytes(path);
    std::string_view all(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    std::vector<float> xyz;
    size_t pos = 0, width = 0;
    int line_no = 0, first_data_line = 0;
    bool seen_content = false;
    while (pos < all.size()) {
        size_t nl = all.find('\n', pos);
        if (nl == std::string_view::npos) nl = all.size();
        std::string_view line = all.substr(pos, nl - pos);
        pos = nl + 1;
        ++line_no;
        line = line.substr(0, line.find('#'));
        std::vector<std::string_view> tokens;
        for (size_t i = 0; i < line.size();) {
            while (i < line.size() && (line[i] == ',' || line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
            size_t j = i;
            while (j < line.size() && line[j] != ',' && line[j] != ' ' && line[j] != '\t' && line[j] != '\r') ++j;
            if (j > i) tokens.push_back(line.substr(i, j - i));
            i = j;
        }
        if (tokens.empty()) continue;
        std::vector<double> vals(tokens.size());
        size_t bad = tokens.size();
        for (size_t k = 0; k < tokens.size() && bad == tokens.size(); ++k)
            if (!parse_number(tokens[k], vals[k])) bad = k;
        bool first = !seen_content;
        seen_content = true;
        if (bad < tokens.size()) {
            if (first) continue;  // the header line
            fail(path, "line " + std::to_string(line_no) + ": '" + std::string(tokens[bad]) + "' is not a number");
        }
        std::string where = "line " + std::to_string(line_no);
        if (tokens.size() < 3) fail(path, where + ": " + std::to_string(tokens.size()) + " values, need x, y, z");
        if (width == 0) {
            width = tokens.size();
            first_data_line = line_no;
        } else if (tokens.size() != width) {
            fail(path, where + ": " + std::to_string(tokens.size()) + " values, but line " +
                           std::to_string(first_data_line) + " has " + std::to_string(width));
        }
        const int cols = keep_normals && width >= 6 ? 6 : 3;
        for (int k = 0; k < cols; ++k) {
            if (!std::isfinite(vals[size_t(k)]) || !std::isfinite(float(vals[size_t(k)])))
                fail(path, where + ": non-finite " + (k < 3 ? "coordinate" : "normal"));
            xyz.push_back(float(vals[size_t(k)]));
        }
    }
    if (xyz.empty()) fail(path, "no " + what + " in the file");
    const int64_t cols = keep_normals && width >= 6 ? 6 : 3;
    const int64_t m = int64_t(xyz.size()) / cols;  // before the move below
    return HostTensor({m, cols}, std::move(xyz));
}

}  // namespace vtloc::io
