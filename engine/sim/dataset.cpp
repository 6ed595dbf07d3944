// Reading and writing the `vtloc-synth/1` layout (docs/dataset.md).
#include "engine/sim/dataset.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <type_traits>
#include <utility>

#include "base/error.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace vtloc::sim {

namespace {

std::string read_text(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    if (!f) throw Error(p.string() + ": cannot read (missing or unreadable)");
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

json read_json(const fs::path& p) {
    try {
        return json::parse(read_text(p));
    } catch (const json::exception& e) {
        throw Error(p.string() + ": not valid JSON (" + e.what() + ")");
    }
}

template <class T>
T field(const json& j, const char* key, const fs::path& p) {
    if (!j.is_object() || !j.contains(key)) throw Error(p.string() + ": missing field '" + key + "'");
    if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
        // nlohmann casts a float (1.5e39) or an out-of-range integer to T: undefined behaviour (UBSan, fuzzing).
        const json& v = j.at(key);
        if (!v.is_number()) throw Error(p.string() + ": field '" + key + "' has the wrong type");
        const bool fits = v.is_number_unsigned() ? std::in_range<T>(v.get<uint64_t>())
                          : v.is_number_integer() ? std::in_range<T>(v.get<int64_t>())
                                                  : false;
        if (!fits) throw Error(p.string() + ": field '" + key + "' must be an integer in the range of its type");
        return v.is_number_unsigned() ? T(v.get<uint64_t>()) : T(v.get<int64_t>());
    }
    try {
        return j.at(key).get<T>();
    } catch (const json::exception&) {
        throw Error(p.string() + ": field '" + key + "' has the wrong type");
    }
}

// An optional field: `fallback` when absent, one-line error when of the wrong type
// (json::value would throw its own exception type past the readers' callers).
template <class T>
T optional_field(const json& j, const char* key, T fallback, const fs::path& p) {
    if (!j.is_object() || !j.contains(key)) return fallback;
    return field<T>(j, key, p);
}

std::vector<std::string> split_commas(const std::string& line) {
    std::vector<std::string> out;
    std::string cur;
    for (char c : line) {
        if (c == ',') {
            out.push_back(cur);
            cur.clear();
        } else if (c != '\r') {
            cur += c;
        }
    }
    out.push_back(cur);
    return out;
}

// A CSV with a header: rows as maps from column name to text.
struct Csv {
    std::vector<std::string> header;
    std::vector<std::vector<std::string>> rows;
    std::map<std::string, size_t> col;

    size_t index(const std::string& name, const fs::path& p) const {
        auto it = col.find(name);
        if (it == col.end()) throw Error(p.string() + ": missing column '" + name + "'");
        return it->second;
    }
};

Csv read_csv(const fs::path& p) {
    std::istringstream in(read_text(p));
    Csv c;
    std::string line;
    if (!std::getline(in, line)) throw Error(p.string() + ": empty file (no header)");
    c.header = split_commas(line);
    for (size_t i = 0; i < c.header.size(); ++i) c.col[c.header[i]] = i;
    size_t lineno = 1;
    while (std::getline(in, line)) {
        ++lineno;
        if (line.empty() || line == "\r") continue;
        auto cells = split_commas(line);
        if (cells.size() != c.header.size())
            throw Error(p.string() + ":" + std::to_string(lineno) + ": " + std::to_string(cells.size()) +
                        " values, the header has " + std::to_string(c.header.size()));
        c.rows.push_back(std::move(cells));
    }
    return c;
}

double number(const std::string& s, const fs::path& p, size_t row, const std::string& column) {
    char* end = nullptr;
    double v = std::strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0' || !std::isfinite(v))
        throw Error(p.string() + ":" + std::to_string(row + 2) + ": column '" + column + "' is not a finite number ('" +
                    s + "')");
    return v;
}

std::string fmt(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.9g", v);
    return b;
}

const char* kTouchColumns[] = {"id", "split", "order", "image", "cx", "cy", "cz", "nx", "ny", "nz",
                               "r00", "r01", "r02", "r10", "r11", "r12", "r20", "r21", "r22",
                               "tx", "ty", "tz", "press_mm", "spin_deg", "tilt_deg", "dx", "dy", "dz",
                               "q00", "q01", "q02", "q10", "q11", "q12", "q20", "q21", "q22", "qx", "qy", "qz"};

// points.csv: x y z nx ny nz, as many rows as dataset.json's n_points (when > 0).
void read_points(ObjectRecord& o, const fs::path& dir, int n_points) {
    fs::path pp = dir / "points.csv";
    Csv pc = read_csv(pp);
    const char* pcols[] = {"x", "y", "z", "nx", "ny", "nz"};
    size_t pidx[6];
    for (int k = 0; k < 6; ++k) pidx[k] = pc.index(pcols[k], pp);
    o.n_points = int(pc.rows.size());
    if (o.n_points == 0) throw Error(pp.string() + ": no points");
    if (n_points > 0 && o.n_points != n_points)
        throw Error(pp.string() + ": " + std::to_string(o.n_points) + " points, dataset.json says " +
                    std::to_string(n_points));
    o.points = HostTensor({int64_t(o.n_points), 6});
    for (size_t r = 0; r < pc.rows.size(); ++r)
        for (int k = 0; k < 6; ++k) o.points.data[r * 6 + size_t(k)] = float(number(pc.rows[r][pidx[k]], pp, r, pcols[k]));
}

// Row `r` of touches.csv; `ix` maps the columns present to their index (absent SE(3) columns read as identity).
TouchRecord touch_row(const Csv& tc, const std::map<std::string, size_t>& ix, const fs::path& tp, size_t r) {
    auto num = [&](const char* c, double fallback) {
        auto it = ix.find(c);
        return it == ix.end() ? fallback : number(tc.rows[r][it->second], tp, r, c);
    };
    TouchRecord t;
    t.id = int(num("id", 0));
    t.split = tc.rows[r][ix.at("split")];
    if (t.split != "train" && t.split != "test" && t.split != "extra")
        throw Error(tp.string() + ":" + std::to_string(r + 2) + ": split '" + t.split + "' (train, test or extra)");
    t.order = int(num("order", -1));
    t.image = tc.rows[r][ix.at("image")];
    const char* c3[] = {"cx", "cy", "cz"};
    const char* n3[] = {"nx", "ny", "nz"};
    const char* t3[] = {"tx", "ty", "tz"};
    const char* d3[] = {"dx", "dy", "dz"};
    const char* q3[] = {"qx", "qy", "qz"};
    for (int k = 0; k < 3; ++k) {
        t.contact[size_t(k)] = num(c3[k], 0);
        t.normal[size_t(k)] = num(n3[k], 0);
        t.t[size_t(k)] = num(t3[k], 0);
        t.motion[size_t(k)] = num(d3[k], 0);
        t.rel_t[size_t(k)] = num(q3[k], 0);
    }
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            // Appended, not "r" + ...: GCC 12's -Wrestrict false positive on literal + string.
            const std::string ab = std::to_string(a).append(std::to_string(b));
            const std::string rn = std::string("r").append(ab), qn = std::string("q").append(ab);
            t.R[size_t(a * 3 + b)] = num(rn.c_str(), a == b ? 1 : 0);
            t.rel_R[size_t(a * 3 + b)] = num(qn.c_str(), a == b ? 1 : 0);
        }
    t.press_mm = num("press_mm", 0);
    t.spin_deg = num("spin_deg", 0);
    t.tilt_deg = num("tilt_deg", 0);
    return t;
}

// touches.csv: one TouchRecord a row, ids increasing, at least one test touch.
void read_touches(ObjectRecord& o, const fs::path& dir) {
    fs::path tp = dir / "touches.csv";
    Csv tc = read_csv(tp);
    std::map<std::string, size_t> ix;
    for (const char* c : kTouchColumns) {
        // The SE(3) columns are optional for a user's own data.
        bool optional = c[0] == 'q' || c[0] == 'r' || c[0] == 't' || std::string(c) == "press_mm" ||
                        std::string(c) == "spin_deg" || std::string(c) == "tilt_deg";
        if (optional && !tc.col.count(c)) continue;
        ix[c] = tc.index(c, tp);
    }
    for (size_t r = 0; r < tc.rows.size(); ++r) o.touches.push_back(touch_row(tc, ix, tp, r));
    for (size_t i = 1; i < o.touches.size(); ++i)
        if (o.touches[i].id <= o.touches[i - 1].id)
            throw Error(tp.string() + ": touch ids must increase (row " + std::to_string(i + 2) + ")");
    if (o.touches_of("test").empty()) throw Error(tp.string() + ": no test touches (the candidates)");
}

ObjectRecord read_object(const fs::path& root, const json& entry, const fs::path& index_path, int n_points) {
    ObjectRecord o;
    o.name = field<std::string>(entry, "name", index_path);
    fs::path dir = root / "objects" / o.name;
    o.folder = dir.string();
    if (!fs::is_directory(dir)) throw Error(dir.string() + ": object folder listed in dataset.json is missing");
    fs::path oj = dir / "object.json";
    json j = read_json(oj);
    if (field<std::string>(j, "name", oj) != o.name) throw Error(oj.string() + ": name does not match its folder");
    o.source = optional_field<std::string>(j, "source", std::string(), oj);
    o.subset = field<std::string>(entry, "subset", index_path);
    if (o.subset != "uniform" && o.subset != "non-uniform")
        throw Error(index_path.string() + ": object '" + o.name + "' has subset '" + o.subset +
                    "' (uniform or non-uniform)");
    o.dn_share = optional_field<double>(entry, "dn_share", optional_field<double>(j, "dn_share", 0.0, oj), index_path);
    o.object_split = field<std::string>(entry, "object_split", index_path);
    if (o.object_split != "seen" && o.object_split != "unseen")
        throw Error(index_path.string() + ": object '" + o.name + "' has object_split '" + o.object_split +
                    "' (seen or unseen)");
    o.scale_mm = optional_field<double>(j, "scale_mm", 0.0, oj);
    o.diameter_mm = optional_field<double>(j, "diameter_mm", 0.0, oj);
    o.sample_seed = optional_field<uint64_t>(j, "sample_seed", uint64_t(0), oj);
    if (j.contains("symmetry")) o.symmetry = symmetry_from_json(j["symmetry"], oj.string());

    read_points(o, dir, n_points);
    read_touches(o, dir);
    o.has_mesh = fs::exists(dir / "mesh.ply");
    o.has_background = fs::exists(dir / "background.png");
    return o;
}

}  // namespace

HostTensor ObjectRecord::candidates() const {
    auto test = touches_of("test");
    HostTensor c({int64_t(test.size()), 3});
    for (size_t i = 0; i < test.size(); ++i)
        for (int k = 0; k < 3; ++k) c.data[i * 3 + size_t(k)] = float(test[i]->contact[size_t(k)]);
    return c;
}

std::vector<const TouchRecord*> ObjectRecord::touches_of(const std::string& split) const {
    std::vector<const TouchRecord*> out;
    for (const auto& t : touches)
        if (t.split == split) out.push_back(&t);
    return out;
}

Dataset read_dataset(const std::string& root_arg) {
    fs::path root(root_arg);
    fs::path index = root / "dataset.json";
    if (!fs::is_directory(root)) throw Error(root_arg + ": not a folder");
    if (!fs::exists(index)) throw Error(root_arg + ": not a dataset (no dataset.json; see docs/dataset.md)");
    json j = read_json(index);
    std::string format = field<std::string>(j, "format", index);
    if (format != kDatasetFormat)
        throw Error(index.string() + ": format '" + format + "', this engine reads '" + kDatasetFormat + "'");
    Dataset d;
    d.root = root_arg;
    d.seed = optional_field<uint64_t>(j, "seed", uint64_t(0), index);
    d.n_points = field<int>(j, "n_points", index);
    if (d.n_points < 1) throw Error(index.string() + ": field 'n_points' must be >= 1, got " + std::to_string(d.n_points));
    json s = field<json>(j, "sensor", index);
    d.sensor.height = field<int>(s, "height", index);
    d.sensor.width = field<int>(s, "width", index);
    d.sensor.mm_per_px = field<double>(s, "mm_per_px", index);
    d.sensor.calibration = optional_field<std::string>(s, "calibration", std::string(), index);
    if (d.sensor.height <= 0 || d.sensor.width <= 0 || !(d.sensor.mm_per_px > 0))
        throw Error(index.string() + ": sensor size and mm_per_px must be positive");
    json objs = field<json>(j, "objects", index);
    if (!objs.is_array() || objs.empty()) throw Error(index.string() + ": no objects");
    for (const json& e : objs) d.objects.push_back(read_object(root, e, index, d.n_points));
    return d;
}

void write_object_json(const std::string& path, const ObjectRecord& o) {
    json j = {{"name", o.name},         {"source", o.source},         {"scale_mm", o.scale_mm},
              {"diameter_mm", o.diameter_mm}, {"subset", o.subset},   {"dn_share", o.dn_share},
              {"n_points", o.n_points}, {"sample_seed", o.sample_seed}};
    j["symmetry"] = symmetry_json(o.symmetry);
    write_file_atomic(path, j.dump(1) + "\n");
}

void write_points_csv(const std::string& path, const HostTensor& p) {
    std::string s = "x,y,z,nx,ny,nz\n";
    for (int64_t i = 0; i < p.shape[0]; ++i) {
        for (int k = 0; k < 6; ++k) {
            if (k) s += ',';
            s += fmt(p.data[size_t(i) * 6 + size_t(k)]);
        }
        s += "\n";
    }
    write_file_atomic(path, s);
}

void write_touches_csv(const std::string& path, const std::vector<TouchRecord>& touches) {
    std::string s;
    for (size_t i = 0; i < std::size(kTouchColumns); ++i) {
        if (i) s += ',';
        s += kTouchColumns[i];
    }
    s += "\n";
    for (const auto& t : touches) {
        std::vector<std::string> v = {std::to_string(t.id), t.split, std::to_string(t.order), t.image};
        for (double x : t.contact) v.push_back(fmt(x));
        for (double x : t.normal) v.push_back(fmt(x));
        for (double x : t.R) v.push_back(fmt(x));
        for (double x : t.t) v.push_back(fmt(x));
        v.push_back(fmt(t.press_mm));
        v.push_back(fmt(t.spin_deg));
        v.push_back(fmt(t.tilt_deg));
        for (double x : t.motion) v.push_back(fmt(x));
        for (double x : t.rel_R) v.push_back(fmt(x));
        for (double x : t.rel_t) v.push_back(fmt(x));
        for (size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + v[i];
        s += "\n";
    }
    write_file_atomic(path, s);
}

void write_dataset_json(const std::string& path, const Dataset& d) {
    json objs = json::array();
    for (const auto& o : d.objects)
        objs.push_back({{"name", o.name}, {"subset", o.subset}, {"dn_share", o.dn_share},
                        {"object_split", o.object_split}});
    json j = {{"format", kDatasetFormat},
              {"seed", d.seed},
              {"sensor",
               {{"height", d.sensor.height},
                {"width", d.sensor.width},
                {"mm_per_px", d.sensor.mm_per_px},
                {"calibration", d.sensor.calibration}}},
              {"n_points", d.n_points},
              {"objects", objs}};
    write_file_atomic(path, j.dump(1) + "\n");
}

}  // namespace vtloc::sim
