// Loading a weight file for the public API: the config schema (SPEC section 7)
// and every tensor the network needs are checked up front, so a wrong file
// fails at load with one message instead of at the first touch.
#include <cmath>
#include <filesystem>
#include <optional>

#include "engine/api/api_internal.h"
#include "engine/error.h"
#include "engine/model/gma.h"
#include "engine/safetensors.h"

namespace vtloc::api {

namespace {

using nlohmann::json;

// Reads the config with messages that name the key ("point.sa[1].radii").
class ConfigReader {
public:
    explicit ConfigReader(std::string source) : source_(std::move(source)) {}

    [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
        throw Error(source_ + ": model config: '" + key + "' " + problem);
    }
    const json& at(const json& obj, const std::string& path, const char* key) const {
        if (!obj.contains(key)) fail(path + key, "is missing");
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
    int64_t field_int(const json& obj, const std::string& path, const char* key, int64_t lo) const {
        return integer(at(obj, path, key), path + key, lo);
    }
    // A list of integers >= 1 (of `n` entries unless n < 0).
    size_t int_list(const json& v, const std::string& key, int n = -1) const {
        if (!v.is_array() || (n >= 0 && v.size() != size_t(n)))
            fail(key, n >= 0 ? "must be a list of " + std::to_string(n) + " integers" : "must be a list of integers");
        for (size_t i = 0; i < v.size(); ++i) integer(v[i], key + "[" + std::to_string(i) + "]", 1);
        return v.size();
    }
    size_t int_list(const json& obj, const std::string& path, const char* key, int n = -1) const {
        return int_list(at(obj, path, key), path + key, n);
    }

private:
    std::string source_;
};

void check_config(const json& cfg, const std::string& source) {
    ConfigReader r(source);
    if (!cfg.contains("name") || !cfg.at("name").is_string()) r.fail("name", "must be a string");
    r.field_int(cfg, "", "C", 1);
    r.field_int(cfg, "", "K", 1);
    const json& t = r.object(cfg, "", "tactile");
    r.field_int(t, "tactile.", "crop", 1);
    r.field_int(t, "tactile.", "in_size", 1);
    r.int_list(t, "tactile.", "widths", 4);
    r.int_list(t, "tactile.", "blocks", 4);
    r.int_list(t, "tactile.", "mlp");
    const json& p = r.object(cfg, "", "point");
    r.field_int(p, "point.", "n_points", 1);
    if (!r.at(p, "point.", "use_normals").is_boolean()) r.fail("point.use_normals", "must be true or false");
    const json& sa = r.at(p, "point.", "sa");
    if (!sa.is_array() || sa.empty()) r.fail("point.sa", "must be a non-empty list of stages");
    for (size_t i = 0; i < sa.size(); ++i) {
        const std::string path = "point.sa[" + std::to_string(i) + "].";
        if (!sa[i].is_object()) r.fail(path.substr(0, path.size() - 1), "must be an object");
        r.field_int(sa[i], path, "npoint", 1);
        const json& radii = r.at(sa[i], path, "radii");
        size_t scales = r.int_list(sa[i], path, "nsample");
        if (!radii.is_array() || radii.size() != scales)
            r.fail(path + "radii", "must list one radius per nsample entry");
        for (const json& x : radii)
            if (!x.is_number() || !(x.get<double>() > 0)) r.fail(path + "radii", "must hold positive numbers");
        const json& mlps = r.at(sa[i], path, "mlps");
        if (!mlps.is_array() || mlps.size() != scales) r.fail(path + "mlps", "must hold one MLP per scale");
        for (size_t s = 0; s < scales; ++s) r.int_list(mlps[s], path + "mlps[" + std::to_string(s) + "]");
    }
    if (p.at("n_points").get<int64_t>() < sa[0].at("npoint").get<int64_t>())
        r.fail("point.n_points", "must be at least point.sa[0].npoint");
    r.int_list(p, "point.", "group_all_mlp");
    r.int_list(p, "point.", "mlp");
    if (!cfg.contains("gma")) r.fail("gma", "is missing (null for none)");
    if (!cfg.at("gma").is_null()) {
        const json& g = r.object(cfg, "", "gma");
        r.field_int(g, "gma.", "n_points", 1);
        r.field_int(g, "gma.", "channels", 1);
        r.int_list(g, "gma.", "decoder");
    }
    const json& head = r.at(cfg, "", "head");
    if (head != "ilu" && head != "mcr") r.fail("head", "must be \"ilu\" or \"mcr\"");
    if (head == "ilu") {
        const json& ilu = r.object(cfg, "", "ilu");
        r.integer(r.at(ilu, "ilu.", "iters"), "ilu.iters", 0, 64);
        r.field_int(ilu, "ilu.", "head_hidden", 1);
    } else {
        r.int_list(r.object(cfg, "", "mcr"), "mcr.", "hidden");
    }
    // Optional: the sensor the model was trained on (absent or null: none).
    if (cfg.contains("sensor") && !cfg.at("sensor").is_null()) {
        const json& s = r.object(cfg, "", "sensor");
        const json& mm = r.at(s, "sensor.", "mm_per_px");
        if (!mm.is_number() || !std::isfinite(mm.get<double>()) || !(mm.get<double>() > 0))
            r.fail("sensor.mm_per_px", "must be a finite number > 0");
        r.field_int(s, "sensor.", "height", 1);
        r.field_int(s, "sensor.", "width", 1);
    }
}

// Builds the whole network once (on a copy: building adds folded tensors)
// and checks every weight it reads against the file.
void check_tensors(const WeightStore& weights) {
    const json& cfg = weights.config();
    WeightStore w = weights;
    const bool gma = !cfg.at("gma").is_null();
    if (gma) split_weight_rows(w, "gma.weight", kPortableBindingBytes);
    VtlocGraphSpec spec;
    spec.image_height = spec.image_width = 8;
    spec.n_points = cfg.at("point").at("sa").at(0).at("npoint").get<int64_t>();
    spec.n_candidates = cfg.at("K").get<int64_t>();
    spec.gma = gma;
    Graph g = build_vtloc_graph(w, spec);
    for (const Value& v : g.values())
        if (v.kind == ValueKind::Weight) w.get(v.name, v.shape);
}

}  // namespace

WeightStore load_checked_weights(const std::string& path, ModelInfo& info) {
    if (!std::filesystem::exists(path)) throw Error(path + ": no such file");
    if (std::filesystem::is_directory(path)) throw Error(path + ": is a directory, not a weight file");
    std::optional<SafetensorsFile> loaded;
    try {
        loaded.emplace(SafetensorsFile::load(path));
    } catch (const vtloc::Error& e) {
        throw Error(std::string(e.what()) + " (not a safetensors weight file?)");
    }
    const SafetensorsFile& file = *loaded;
    WeightStore w = WeightStore::from_file(file);
    const json& cfg = w.config();
    check_config(cfg, path);
    try {
        check_tensors(w);
    } catch (const vtloc::Error& e) {
        std::string msg = e.what();
        if (msg.rfind(path + ": ", 0) == 0) msg = msg.substr(path.size() + 2);  // WeightStore names the file
        throw Error(path + ": " + msg + " (the tensors do not fit the file's config '" +
                    cfg.at("name").get<std::string>() + "')");
    }

    info = ModelInfo{};
    info.path = path;
    info.name = cfg.at("name").get<std::string>();
    info.config_json = cfg.dump(2);
    info.head = cfg.at("head").get<std::string>();
    info.feature_size = cfg.at("C").get<int64_t>();
    info.default_k = cfg.at("K").get<int64_t>();
    info.default_iters = info.head == "ilu" ? cfg.at("ilu").at("iters").get<int>() : 0;
    info.use_normals = cfg.at("point").at("use_normals").get<bool>();
    info.has_gma = !cfg.at("gma").is_null();
    info.crop = cfg.at("tactile").at("crop").get<int64_t>();
    info.input_size = cfg.at("tactile").at("in_size").get<int64_t>();
    info.sample_points = cfg.at("point").at("n_points").get<int64_t>();
    info.min_points = cfg.at("point").at("sa").at(0).at("npoint").get<int64_t>();
    if (cfg.contains("sensor") && !cfg.at("sensor").is_null()) {
        const json& s = cfg.at("sensor");
        info.sensor = SensorInfo{s.at("mm_per_px").get<double>(), s.at("height").get<int>(), s.at("width").get<int>()};
    }
    for (const TensorInfo& t : file.tensors()) {
        info.tensors.push_back({t.name, dtype_name(t.dtype), t.shape});
        if (t.dtype == DType::F32 || t.dtype == DType::F16 || t.dtype == DType::BF16)
            info.parameter_count += uint64_t(numel(t.shape));
    }
    info.size_mib = double(info.parameter_count) * 4.0 / (1024.0 * 1024.0);
    info.file_bytes = std::filesystem::file_size(path);
    return w;
}

ModelInfo inspect_model(const std::string& path) {
    return guarded([&] {
        ModelInfo info;
        load_checked_weights(path, info);
        return info;
    });
}

VtlocRunner& Model::Impl::runner(Backend b) {
    if (b == Backend::Gpu) {
        if (!gpu_runner) throw Error("this model was loaded without a GPU context; use Backend::Cpu");
        return *gpu_runner;
    }
    if (!cpu_runner) {
        ModelInfo again;
        cpu_runner = std::make_unique<VtlocRunner>(load_checked_weights(info.path, again), nullptr);
    }
    return *cpu_runner;
}

namespace {

std::unique_ptr<Model::Impl> make_model(rt::Context* gpu, const std::string& path) {
    auto m = std::make_unique<Model::Impl>();
    WeightStore w = load_checked_weights(path, m->info);
    std::error_code ec;
    std::string canonical = std::filesystem::weakly_canonical(path, ec).string();
    m->key = (ec ? path : canonical) + "|" + std::to_string(m->info.file_bytes) + "|" + m->info.config_json;
    m->gpu = gpu;
    if (gpu) m->gpu_runner = std::make_unique<VtlocRunner>(std::move(w), gpu);
    else m->cpu_runner = std::make_unique<VtlocRunner>(std::move(w), nullptr);
    return m;
}

}  // namespace

Model::Model(Context& context, const std::string& path) {
    impl_ = guarded([&] { return make_model(&context.impl_->ctx, path); });
}

Model::Model(const std::string& path) {
    impl_ = guarded([&] { return make_model(nullptr, path); });
}

Model::~Model() = default;
Model::Model(Model&&) noexcept = default;
Model& Model::operator=(Model&&) noexcept = default;

const ModelInfo& Model::info() const { return impl_->info; }

}  // namespace vtloc::api
