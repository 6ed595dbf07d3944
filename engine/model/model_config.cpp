#include "engine/model/model_config.h"

#include <climits>
#include <cmath>

#include "base/error.h"

namespace vtloc {

namespace {

using nlohmann::json;

// Reads the JSON with messages that name the key ("point.sa[1].radii").
class Reader {
public:
    explicit Reader(const std::string& source) : source_(source) {}

    [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
        throw Error(source_ + ": model config: '" + key + "' " + problem);
    }
    const json& at(const json& obj, const std::string& path, const char* key) const {
        if (!obj.is_object() || !obj.contains(key)) fail(path + key, "is missing");
        return obj.at(key);
    }
    const json& object(const json& obj, const std::string& path, const char* key) const {
        const json& v = at(obj, path, key);
        if (!v.is_object()) fail(path + key, "must be an object");
        return v;
    }
    int64_t integer(const json& v, const std::string& key, int64_t lo, int64_t hi = INT32_MAX) const {
        if (!v.is_number_integer() || v.get<int64_t>() < lo || v.get<int64_t>() > hi)
            fail(key, "must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi));
        return v.get<int64_t>();
    }
    int64_t field_int(const json& obj, const std::string& path, const char* key, int64_t lo = 1) const {
        return integer(at(obj, path, key), path + key, lo);
    }
    // A list of integers >= 1 (of `n` entries unless n < 0).
    std::vector<int64_t> int_list(const json& v, const std::string& key, int n = -1) const {
        if (!v.is_array() || (n >= 0 && v.size() != size_t(n)))
            fail(key, n >= 0 ? "must be a list of " + std::to_string(n) + " integers" : "must be a list of integers");
        std::vector<int64_t> out;
        for (size_t i = 0; i < v.size(); ++i) out.push_back(integer(v[i], key + "[" + std::to_string(i) + "]", 1));
        return out;
    }
    std::vector<int64_t> int_list(const json& obj, const std::string& path, const char* key, int n = -1) const {
        return int_list(at(obj, path, key), path + key, n);
    }
    double positive(const json& obj, const std::string& path, const char* key) const {
        const json& v = at(obj, path, key);
        if (!v.is_number() || !std::isfinite(v.get<double>()) || !(v.get<double>() > 0))
            fail(path + key, "must be a finite number > 0");
        return v.get<double>();
    }

private:
    const std::string& source_;
};

SaStageConfig sa_stage(const Reader& r, const json& st, const std::string& path) {
    if (!st.is_object()) r.fail(path.substr(0, path.size() - 1), "must be an object");
    SaStageConfig s;
    s.npoint = r.field_int(st, path, "npoint");
    s.nsample = r.int_list(st, path, "nsample");
    const size_t scales = s.nsample.size();
    if (scales == 0) r.fail(path + "nsample", "must list at least one scale");
    const json& radii = r.at(st, path, "radii");
    if (!radii.is_array() || radii.size() != scales) r.fail(path + "radii", "must list one radius per nsample entry");
    for (const json& x : radii) {
        if (!x.is_number() || !std::isfinite(x.get<double>()) || !(x.get<double>() > 0))
            r.fail(path + "radii", "must hold positive numbers");
        s.radii.push_back(x.get<double>());
    }
    const json& mlps = r.at(st, path, "mlps");
    if (!mlps.is_array() || mlps.size() != scales) r.fail(path + "mlps", "must hold one MLP per scale");
    for (size_t i = 0; i < scales; ++i) {
        const std::string key = path + "mlps[" + std::to_string(i) + "]";
        s.mlps.push_back(r.int_list(mlps[i], key));
        if (s.mlps.back().empty()) r.fail(key, "must list at least one layer");
    }
    return s;
}

PointConfig read_point(const Reader& r, const json& cfg) {
    const json& p = r.object(cfg, "", "point");
    PointConfig c;
    c.n_points = r.field_int(p, "point.", "n_points");
    const json& normals = r.at(p, "point.", "use_normals");
    if (!normals.is_boolean()) r.fail("point.use_normals", "must be true or false");
    c.use_normals = normals.get<bool>();
    const json& sa = r.at(p, "point.", "sa");
    if (!sa.is_array() || sa.empty()) r.fail("point.sa", "must be a non-empty list of stages");
    for (size_t i = 0; i < sa.size(); ++i) c.sa.push_back(sa_stage(r, sa[i], "point.sa[" + std::to_string(i) + "]."));
    if (c.n_points < c.min_points()) r.fail("point.n_points", "must be at least point.sa[0].npoint");
    c.group_all = r.int_list(p, "point.", "group_all_mlp");
    if (c.group_all.empty()) r.fail("point.group_all_mlp", "must list at least one layer");
    c.mlp = r.int_list(p, "point.", "mlp");
    return c;
}

}  // namespace

ModelConfig ModelConfig::parse(const nlohmann::json& cfg, const std::string& source) {
    Reader r(source);
    if (!cfg.is_object()) throw Error(source + ": model config: must be a JSON object");
    ModelConfig c;
    c.source_json = cfg;
    if (!cfg.contains("name") || !cfg.at("name").is_string()) r.fail("name", "must be a string");
    c.name = cfg.at("name").get<std::string>();
    c.C = r.field_int(cfg, "", "C");
    c.K = r.integer(r.at(cfg, "", "K"), "K", 1, limits::kMaxTopK);
    const json& t = r.object(cfg, "", "tactile");
    c.tactile.crop = r.field_int(t, "tactile.", "crop");
    c.tactile.in_size = r.field_int(t, "tactile.", "in_size");
    c.tactile.widths = r.int_list(t, "tactile.", "widths", 4);
    c.tactile.blocks = r.int_list(t, "tactile.", "blocks", 4);
    c.tactile.mlp = r.int_list(t, "tactile.", "mlp");
    c.point = read_point(r, cfg);
    if (!cfg.contains("gma")) r.fail("gma", "is missing (null for none)");
    if (!cfg.at("gma").is_null()) {
        const json& g = r.object(cfg, "", "gma");
        c.gma = GmaConfig{r.field_int(g, "gma.", "n_points"), r.field_int(g, "gma.", "channels"),
                          r.int_list(g, "gma.", "decoder")};
    }
    const json& head_key = r.at(cfg, "", "head");
    if (head_key != "ilu" && head_key != "mcr") r.fail("head", "must be \"ilu\" or \"mcr\"");
    if (head_key == "ilu") {
        c.head = Head::Ilu;
        const json& ilu = r.object(cfg, "", "ilu");
        c.ilu_iters = int(r.integer(r.at(ilu, "ilu.", "iters"), "ilu.iters", 0, limits::kMaxIters));
        c.ilu_head_hidden = r.field_int(ilu, "ilu.", "head_hidden");
    } else {
        c.head = Head::Mcr;
        c.mcr_hidden = r.int_list(r.object(cfg, "", "mcr"), "mcr.", "hidden");
    }
    // Optional: the sensor the model was trained on (absent or null: none).
    if (cfg.contains("sensor") && !cfg.at("sensor").is_null()) {
        const json& s = r.object(cfg, "", "sensor");
        c.sensor = SensorConfig{r.positive(s, "sensor.", "mm_per_px"), r.field_int(s, "sensor.", "height"),
                                r.field_int(s, "sensor.", "width")};
    }
    return c;
}

}  // namespace vtloc
