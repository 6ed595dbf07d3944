#include "engine/model/vtloc_runner.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/model/heads.h"
#include "engine/model/point_encoder.h"
#include "engine/model/post.h"
#include "engine/model/prepared_weights.h"
#include "runtime/context.h"
#include "engine/ops/build.h"

namespace vtloc {

namespace {

constexpr int kMaxIters = limits::kMaxIters;  // one recorded graph serves every N in 0..64

std::string spec_key(const VtlocGraphSpec& s, bool profile) {
    return std::to_string(s.image_height) + "x" + std::to_string(s.image_width) + "/b" + std::to_string(s.batch) +
           "/n" + std::to_string(s.n_points) + "/o" + std::to_string(s.encode_object) + "/m" +
           std::to_string(s.n_candidates) + "/k" + std::to_string(s.k) + "/g" + std::to_string(s.gma) + "/i" +
           std::to_string(s.max_iters) + "/s" + std::to_string(s.symmetry_order) + "/p" + std::to_string(profile);
}

}  // namespace

struct VtlocRunner::Compiled {
    Graph graph;
    std::unique_ptr<GpuExecutor> gpu;
    std::vector<NodeMs> cpu_times;
};

VtlocRunner::VtlocRunner(PreparedWeights weights, ModelConfig config, rt::Context* gpu)
    : weights_(std::move(weights)), config_(std::move(config)), gpu_(gpu) {}

VtlocRunner::VtlocRunner(const WeightStore& weights, ModelConfig config, rt::Context* gpu)
    : VtlocRunner(prepare_weights(config, weights), config, gpu) {}

VtlocRunner::VtlocRunner(const WeightStore& weights, rt::Context* gpu)
    : VtlocRunner(weights, config_of(weights), gpu) {}

VtlocRunner::~VtlocRunner() = default;

TensorMap VtlocRunner::run(const VtlocGraphSpec& spec_in, const TensorMap& inputs) {
    VtlocGraphSpec spec = spec_in;
    spec.ilu_stepped = ilu_stepped_ && spec.image_height > 0 && spec.max_iters > 0;
    spec.retrieval_apart = retrieval_apart_;
    spec.point_major_rows = point_major_rows_on(gpu_ ? &gpu_->info() : nullptr);
    return run_graph(spec_key(spec, profile_) + (spec.ilu_stepped ? "/stepped" : "") + (retrieval_apart_ ? "/apart" : "") +
                         "/" + schedule_name(schedule_),
                     [&] { return build_vtloc_graph(config_, weights_, spec); }, inputs);
}

TensorMap VtlocRunner::run_graph(const std::string& key, const std::function<Graph()>& build, const TensorMap& inputs) {
    auto& c = compiled_[key];
    if (!c) {
        auto fresh = std::make_unique<Compiled>();
        fresh->graph = build();
        if (gpu_) {
            if (!resident_) resident_ = std::make_shared<ResidentWeights>(*gpu_);
            fresh->gpu = std::make_unique<GpuExecutor>(*gpu_, fresh->graph, weights_, resident_, profile_, false, schedule_);
        }
        c = std::move(fresh);
    }
    last_ = c.get();
    if (gpu_) return c->gpu->run(inputs);
    return run_cpu(c->graph, weights_, inputs, profile_ ? &c->cpu_times : nullptr);
}

std::vector<std::pair<std::string, double>> VtlocRunner::last_node_times() const {
    std::vector<std::pair<std::string, double>> out;
    if (!last_ || !profile_) return out;
    if (!last_->gpu) {
        for (auto& t : last_->cpu_times) out.push_back({t.label, t.ms});
        return out;
    }
    for (auto& t : last_->gpu->node_times()) out.push_back({t.label, t.ms});
    return out;
}

std::vector<std::pair<std::string, uint64_t>> VtlocRunner::last_dispatch_workgroups() const {
    std::vector<std::pair<std::string, uint64_t>> out;
    if (last_ && last_->gpu)
        for (const auto& d : last_->gpu->sequence().dispatch_log())
            out.push_back({d.node, uint64_t(d.groups[0]) * d.groups[1] * d.groups[2]});
    return out;
}

uint32_t VtlocRunner::last_barriers() const { return last_ && last_->gpu ? last_->gpu->sequence().barrier_count() : 0; }

const Graph* VtlocRunner::last_graph() const { return last_ ? &last_->graph : nullptr; }

std::vector<std::string> VtlocRunner::last_dispatch_shaders() const {
    std::vector<std::string> out;
    if (last_ && last_->gpu)
        for (const auto& d : last_->gpu->sequence().dispatch_log()) out.push_back(d.shader);
    return out;
}

VtlocRunner::MemoryUse VtlocRunner::last_memory() const {
    MemoryUse m;
    if (!last_ || !last_->gpu) return m;
    m.weight_bytes = last_->gpu->weight_bytes();
    m.resident_weight_bytes = resident_ ? resident_->bytes() : 0;
    m.arena_bytes = last_->gpu->memory_plan().arena_bytes + last_->gpu->memory_plan().scratch_bytes;
    m.unplanned_bytes = last_->gpu->memory_plan().total_bytes;
    return m;
}

VtlocRunner::AllMemory VtlocRunner::all_memory() const {
    AllMemory m;
    m.resident_weight_bytes = resident_ ? resident_->bytes() : 0;
    for (const auto& [key, c] : compiled_) {
        if (!c || !c->gpu) continue;
        ++m.graphs;
        m.weight_bytes_by_graph += c->gpu->weight_bytes();
        m.arena_bytes += c->gpu->memory_plan().arena_bytes + c->gpu->memory_plan().scratch_bytes;
    }
    return m;
}

EncodedObject VtlocRunner::prepare_object(const HostTensor& cloud, const HostTensor* candidates) const {
    const ModelConfig& cfg = config();
    check_object_cloud(cloud, cfg);
    EncodedObject o;
    o.frame = object_frame(cloud);
    const bool normals = cfg.point.use_normals;
    o.target = to_frame(cloud, o.frame, 6);
    o.cloud = normals ? o.target : to_frame(cloud, o.frame, 3);
    if (candidates) {
        if (candidates->shape.size() != 2 || candidates->shape[1] != 3 || candidates->shape[0] == 0)
            throw Error("candidates must be a non-empty [M, 3] list, got " + shape_str(candidates->shape));
        require_finite(*candidates, "the candidates");
        o.candidates = to_frame(*candidates, o.frame, 3);
    } else {
        o.candidates = to_frame(cloud, o.frame, 3);
    }
    return o;
}

EncodedObject VtlocRunner::encode_object(const HostTensor& cloud, const HostTensor* candidates) {
    EncodedObject o = prepare_object(cloud, candidates);
    VtlocGraphSpec spec;
    spec.n_points = o.cloud.shape[0];
    TensorMap out = run(spec, {{"point.cloud", o.cloud}});
    o.feature = out.at("point.feature");
    for (auto& [name, t] : out)
        if (name != "point.feature") o.indices[name] = t;
    return o;
}

namespace {

struct TouchRun {
    VtlocGraphSpec spec;
    TensorMap inputs;
    int iters = 0;
};

// The graph shape and inputs shared by the cached and one-shot paths.
TouchRun touch_run(const ModelConfig& cfg, const EncodedObject& o, const std::vector<HostTensor>& images,
                   const TouchOptions& opt) {
    if (images.empty()) throw Error("no tactile images given");
    TouchRun r;
    const Shape& s0 = images[0].shape;
    for (const HostTensor& im : images) {
        if (im.shape.size() != 3 || im.shape[2] != 3 || im.type != ElemType::I32)
            throw Error("a tactile image must be an I32 [H, W, 3] tensor of byte values, got " + shape_str(im.shape));
        if (im.shape != s0)
            throw Error("all tactile images of a batch must have one size; got " + shape_str(s0) + " and " +
                        shape_str(im.shape));
    }
    const bool ilu = cfg.head == Head::Ilu;
    r.iters = !ilu ? 0 : opt.iters >= 0 ? opt.iters : cfg.ilu_iters;
    r.spec.image_height = s0[0];
    r.spec.image_width = s0[1];
    r.spec.batch = int64_t(images.size());
    r.spec.n_points = o.cloud.shape[0];
    r.spec.n_candidates = o.candidates.shape[0];
    r.spec.k = opt.k;
    r.spec.gma = opt.gma && cfg.gma.has_value();
    r.spec.max_iters = kMaxIters;
    r.inputs["point.cloud"] = o.cloud;
    r.inputs["candidates"] = o.candidates;
    if (r.spec.gma && !cfg.point.use_normals) r.inputs["gma.target"] = o.target;
    if (ilu) r.inputs["ilu.iters"] = ilu_iters_input(r.iters, kMaxIters);
    if (opt.symmetry && opt.symmetry->order > 1) {
        const Symmetry& sym = *opt.symmetry;
        HostTensor p({1, 3}, {float(sym.axis_point[0]), float(sym.axis_point[1]), float(sym.axis_point[2])});
        HostTensor pn = to_frame(p, o.frame, 3);
        r.spec.symmetry_order = sym.order;
        r.inputs["symmetry"] = symmetry_transforms({pn.data[0], pn.data[1], pn.data[2]}, sym.axis_dir, sym.order);
    }
    if (images.size() == 1) {
        r.inputs["tactile.image"] = images[0];
    } else {
        HostTensor batch(Shape{r.spec.batch, s0[0], s0[1], 3}, ElemType::I32);
        for (size_t b = 0; b < images.size(); ++b)
            std::copy(images[b].data.begin(), images[b].data.end(), batch.data.begin() + std::ptrdiff_t(b * images[b].data.size()));
        r.inputs["tactile.image"] = std::move(batch);
    }
    return r;
}

// Row b of a batch graph's per-touch output [B, ...], shaped as a single-touch
// graph gives it.
HostTensor touch_row(const HostTensor& t, int64_t b, bool keeps_axis) {
    Shape shape(t.shape.begin() + 1, t.shape.end());
    if (keeps_axis) shape.insert(shape.begin(), 1);
    const size_t n = size_t(t.size() / t.shape[0]);
    HostTensor row(shape, t.type);
    std::copy(t.data.begin() + std::ptrdiff_t(size_t(b) * n), t.data.begin() + std::ptrdiff_t(size_t(b + 1) * n), row.data.begin());
    return row;
}

// Touch b's result; a batch graph's shared outputs (the object's) stay out of it.
TouchResult collect(const TensorMap& out, int64_t b, int64_t batch, const EncodedObject& o, int iters) {
    TouchResult r;
    if (batch == 1) {
        r.tensors = out;
    } else {
        for (const TouchOutput& t : touch_outputs()) {
            auto it = out.find(t.name);
            if (it != out.end()) r.tensors[t.name] = touch_row(it->second, b, t.keeps_axis);
        }
    }
    if (r.tensors.count("ilu.c")) {  // the graph holds room for 64 iterations; keep the N that ran
        HostTensor& c = r.tensors["ilu.c"];
        c.shape = {iters, 3};
        c.data.resize(size_t(iters) * 3);
    }
    const HostTensor& cp = r.tensors.at("contact");
    r.tensors["contact"].shape = {3};
    for (int i = 0; i < 3; ++i) r.contact_normalised[size_t(i)] = cp.data[size_t(i)];
    r.contact = from_frame(cp.data.data(), o.frame);
    if (r.tensors.count("topk.index")) {
        r.topk_index = r.tensors["topk.index"].ints();
        r.topk_score = r.tensors["topk.score"].data;
        r.heatmap = r.tensors["heatmap"].data;
    }
    if (r.tensors.count("gma.chamfer")) r.alignment = r.tensors["gma.chamfer"].data.at(0);
    return r;
}

}  // namespace

std::vector<TouchResult> VtlocRunner::localize(const EncodedObject& object, const std::vector<HostTensor>& images,
                                               const TouchOptions& options) {
    if (object.feature.data.empty()) throw Error("the object was not encoded (call encode_object first)");
    TouchRun r = touch_run(config(), object, images, options);
    r.spec.encode_object = false;
    r.inputs["point.feature"] = object.feature;
    TensorMap out = run(r.spec, r.inputs);
    std::vector<TouchResult> results;
    for (int64_t b = 0; b < r.spec.batch; ++b) results.push_back(collect(out, b, r.spec.batch, object, r.iters));
    return results;
}

TouchResult VtlocRunner::localize_once(const HostTensor& image, const HostTensor& cloud, const HostTensor* candidates,
                                       const TouchOptions& options) {
    EncodedObject o = prepare_object(cloud, candidates);
    TouchRun r = touch_run(config(), o, {image}, options);
    r.spec.encode_object = true;
    TensorMap out = run(r.spec, r.inputs);
    return collect(out, 0, 1, o, r.iters);
}

VtlocRunner::Prepared VtlocRunner::prepare_once(const HostTensor& image, const HostTensor& cloud,
                                                const HostTensor* candidates, const TouchOptions& options) {
    EncodedObject o = prepare_object(cloud, candidates);
    TouchRun r = touch_run(config(), o, {image}, options);
    r.spec.encode_object = true;
    r.spec.point_major_rows = point_major_rows_on(gpu_ ? &gpu_->info() : nullptr);
    return {build_vtloc_graph(config_, weights_, r.spec), std::move(r.inputs)};
}

}  // namespace vtloc
