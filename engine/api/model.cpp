// Loading a weight file for the public API (checked up front by
// load_model_file, so a wrong file fails at load with one message).
#include <filesystem>

#include "engine/api/api_internal.h"
#include "engine/model/model_file.h"

namespace vtloc::api {

ModelFile load_checked_model(const std::string& path, ModelInfo& info) {
    ModelFile file = load_model_file(path);
    const ModelConfig& cfg = file.config;
    info = ModelInfo{};
    info.path = path;
    info.name = cfg.name;
    info.config_json = cfg.source_json.dump(2);
    info.head = cfg.head_name();
    info.feature_size = cfg.C;
    info.default_k = cfg.K;
    info.default_iters = cfg.head == Head::Ilu ? cfg.ilu_iters : 0;
    info.use_normals = cfg.point.use_normals;
    info.has_gma = cfg.gma.has_value();
    info.crop = cfg.tactile.crop;
    info.input_size = cfg.tactile.in_size;
    info.sample_points = cfg.point.n_points;
    info.min_points = cfg.point.min_points();
    if (cfg.sensor) info.sensor = SensorInfo{cfg.sensor->mm_per_px, int(cfg.sensor->height), int(cfg.sensor->width)};
    for (const ModelFile::Tensor& t : file.tensors) {
        info.tensors.push_back({t.name, t.dtype, t.shape});
        if (t.floating) info.parameter_count += uint64_t(numel(t.shape));
    }
    info.size_mib = double(info.parameter_count) * 4.0 / (1024.0 * 1024.0);
    info.file_bytes = file.file_bytes;
    return file;
}

ModelInfo inspect_model(const std::string& path) {
    return guarded([&] {
        ModelInfo info;
        load_checked_model(path, info);
        return info;
    });
}

VtlocRunner& Model::Impl::runner(Backend b) {
    if (b == Backend::Gpu) {
        if (!gpu_runner) throw Error("this model was loaded without a GPU context; use Backend::Cpu");
        return *gpu_runner;
    }
    // From the weights loaded with the model, never the file again: it may have
    // changed on disk since.
    if (!cpu_runner) cpu_runner = std::make_unique<VtlocRunner>(gpu_runner->weights(), gpu_runner->config(), nullptr);
    return *cpu_runner;
}

namespace {

std::unique_ptr<Model::Impl> make_model(rt::Context* gpu, const std::string& path) {
    auto m = std::make_unique<Model::Impl>();
    ModelFile f = load_checked_model(path, m->info);
    std::error_code ec;
    std::string canonical = std::filesystem::weakly_canonical(path, ec).string();
    m->key = (ec ? path : canonical) + "|" + std::to_string(m->info.file_bytes) + "|" + m->info.config_json;
    m->gpu = gpu;
    if (gpu) m->gpu_runner = std::make_unique<VtlocRunner>(std::move(f.weights), std::move(f.config), gpu);
    else m->cpu_runner = std::make_unique<VtlocRunner>(std::move(f.weights), std::move(f.config), nullptr);
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
