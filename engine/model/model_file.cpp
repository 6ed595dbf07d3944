#include "engine/model/model_file.h"

#include <cmath>
#include <filesystem>
#include <optional>

#include "base/error.h"
#include "engine/model/prepared_weights.h"
#include "engine/model/vtloc_graph.h"
#include "engine/safetensors.h"

namespace vtloc {

namespace {

// Builds the whole network once on the prepared weights, reading every weight it
// names with the shape the graph expects.
void check_tensors(const ModelConfig& cfg, const WeightStore& w) {
    VtlocGraphSpec spec;
    spec.image_height = spec.image_width = limits::kMinImageSide;
    spec.n_points = cfg.point.min_points();
    spec.n_candidates = cfg.K;
    spec.gma = cfg.gma.has_value();
    Graph g = build_vtloc_graph(cfg, w, spec);
    for (const Value& v : g.values())
        if (v.kind == ValueKind::Weight) w.get(v.name, v.shape);
}

// A NaN or inf weight would flow silently into every output: refuse the file.
void check_finite(const WeightStore& w) {
    for (const std::string& name : w.names()) {
        const HostTensor& t = w.get(name);
        for (size_t i = 0; i < t.data.size(); ++i)
            if (!std::isfinite(t.data[i]))
                throw Error("tensor '" + name + "' holds NaN or inf at element " + std::to_string(i));
    }
}

}  // namespace

ModelFile load_model_file(const std::string& path) {
    if (!std::filesystem::exists(path)) throw Error(path + ": no such file");
    if (std::filesystem::is_directory(path)) throw Error(path + ": is a directory, not a weight file");
    const SafetensorsFile loaded = SafetensorsFile::load(path, "safetensors weight file");
    const WeightStore file = WeightStore::from_file(loaded);
    ModelConfig config = ModelConfig::parse(file.config(), path);
    try {
        check_finite(file);
    } catch (const Error& e) {
        throw Error(path + ": " + e.what());
    }
    std::optional<PreparedWeights> prepared;
    try {
        prepared.emplace(prepare_weights(config, file));
        check_tensors(config, *prepared);
    } catch (const Error& e) {
        std::string msg = e.what();
        if (msg.rfind(path + ": ", 0) == 0) msg = msg.substr(path.size() + 2);  // WeightStore names the file
        throw Error(path + ": " + msg + " (the tensors do not fit the file's config '" + config.name + "')");
    }
    ModelFile m{std::move(*prepared), std::move(config), {}, std::filesystem::file_size(path)};
    for (const TensorInfo& t : loaded.tensors())
        m.tensors.push_back(
            {t.name, dtype_name(t.dtype), t.shape, t.dtype == DType::F32 || t.dtype == DType::F16 || t.dtype == DType::BF16});
    return m;
}

}  // namespace vtloc
