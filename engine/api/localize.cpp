// Touches for the public API: option checks, batches grouped by image size,
// sequences, and the engine's results in object units.
#include <chrono>
#include <map>

#include "engine/api/api_internal.h"
#include "engine/model/tactile_encoder.h"

namespace vtloc::api {

static_assert(kMaxIterations == limits::kMaxIters && kMaxTopK == limits::kMaxTopK,
              "the public limits mirror engine/model/model_config.h");

namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

HostTensor image_tensor(const TactileImage& im) {
    return tactile_image_input(im.rgb.data(), im.rgb.size(), im.height, im.width);
}

TouchOptions touch_options(const ModelInfo& info, const Object::Impl& o, const LocalizeOptions& opt) {
    if (opt.iters < -1 || opt.iters > limits::kMaxIters)
        throw Error("iters must be in 0.." + std::to_string(limits::kMaxIters) + ", got " + std::to_string(opt.iters));
    const int64_t m = int64_t(o.candidates.size() / 3);
    const int64_t k = opt.top_k > 0 ? opt.top_k : info.default_k;
    if (opt.top_k < 0 || k > limits::kMaxTopK)
        throw Error("K must be in 1.." + std::to_string(limits::kMaxTopK) + ", got " + std::to_string(opt.top_k));
    if (k > m)
        throw Error("K = " + std::to_string(k) + (opt.top_k > 0 ? "" : " (the model's default)") +
                    " is larger than the candidate set (" + std::to_string(m) + " candidates)");
    if (opt.symmetry && opt.symmetry->order < 1)
        throw Error("the symmetry order must be >= 1, got " + std::to_string(opt.symmetry->order));
    TouchOptions t;
    t.iters = opt.iters;
    t.k = opt.top_k;
    t.gma = opt.gma;
    if (opt.symmetry) t.symmetry = vtloc::Symmetry{opt.symmetry->axis_point, opt.symmetry->axis_dir, opt.symmetry->order};
    return t;
}

// The frames as the model sees them: each rescaled to the model's sensor pixel
// size when options.mm_per_px is set; empty when it is not (use them as given).
std::vector<TactileImage> model_frames(const ModelInfo& info, const std::vector<TactileImage>& images,
                                       const LocalizeOptions& opt) {
    std::vector<TactileImage> out;
    if (!opt.mm_per_px) return out;
    check_mm_per_px(*opt.mm_per_px, "mm_per_px");
    if (!info.sensor) throw Error(info.path + " has no sensor pixel size in its config; cannot rescale");
    out.reserve(images.size());
    for (const TactileImage& im : images) out.push_back(rescale_frame(im, *opt.mm_per_px, info.sensor->mm_per_px));
    return out;
}

std::array<double, 3> to_object(const float* p, const ObjectFrame& f) { return from_frame(p, f); }

// Shapes as weights_tools.golden writes them (no batch axis of 1, 0-d Chamfer).
std::vector<int64_t> golden_shape(const std::string& name, const Shape& shape) {
    static const char* kFlat[] = {"tactile.feature", "point.feature", "contact", "topk.index", "topk.score", "heatmap"};
    if (name == "gma.chamfer") return {};
    if (name == "gma.cloud" && shape.size() == 3 && shape[0] == 1) return {shape[1], shape[2]};
    for (const char* f : kFlat)
        if (name == f) return {numel(shape)};
    if (name.size() > 4 && name.compare(name.size() - 4, 4, ".fps") == 0) return {numel(shape)};
    return shape;
}

Tensor to_tensor(const std::string& name, const HostTensor& t) {
    Tensor out;
    out.name = name;
    out.shape = golden_shape(name, t.shape);
    if (t.type == ElemType::I32) out.i32 = t.ints();
    else out.f32 = t.data;
    return out;
}

Tensor f32_tensor(const std::string& name, std::vector<int64_t> shape, std::vector<float> v) {
    Tensor t;
    t.name = name;
    t.shape = std::move(shape);
    t.f32 = std::move(v);
    return t;
}

// Every tensor of one touch: the inputs and the normalisation (as the golden
// file has them), the object's branch, then the touch's.
// `rescaled`: the frame after the sensor rescale, when there was one.
std::vector<Tensor> all_tensors(const Object::Impl& o, const TactileImage& image, const vtloc::TouchResult& r,
                                const TactileImage* rescaled) {
    std::vector<Tensor> out;
    Tensor img;
    img.name = "input.tactile";
    img.shape = {image.height, image.width, 3};
    img.u8 = image.rgb;
    out.push_back(std::move(img));
    if (rescaled) {
        Tensor rs;
        rs.name = "tactile.rescaled";
        rs.shape = {rescaled->height, rescaled->width, 3};
        rs.u8 = rescaled->rgb;
        out.push_back(std::move(rs));
    }
    out.push_back(to_tensor("input.cloud", o.raw_cloud));
    out.push_back(f32_tensor("input.candidates", {int64_t(o.candidates.size() / 3), 3}, o.candidates));
    const ObjectFrame& f = o.encoded.frame;
    out.push_back(f32_tensor("point.centre", {3}, {float(f.centre[0]), float(f.centre[1]), float(f.centre[2])}));
    out.push_back(f32_tensor("point.scale", {}, {float(f.scale)}));
    out.push_back(to_tensor("point.cloud", o.encoded.cloud));
    for (auto& [name, t] : o.encoded.indices) out.push_back(to_tensor(name, t));
    out.push_back(to_tensor("point.feature", o.encoded.feature));
    for (auto& [name, t] : r.tensors)
        if (name.rfind("point.", 0) != 0) out.push_back(to_tensor(name, t));
    out.push_back(f32_tensor("contact.object", {3}, {float(r.contact[0]), float(r.contact[1]), float(r.contact[2])}));
    return out;
}

TouchResult convert(const vtloc::TouchResult& r, const Object::Impl& o) {
    TouchResult out;
    out.contact = r.contact;
    out.contact_normalised = r.contact_normalised;
    if (auto it = r.tensors.find("ilu.c"); it != r.tensors.end())
        for (int64_t i = 0; i < it->second.shape[0]; ++i) {
            const float* p = &it->second.data[size_t(i) * 3];
            out.iterates_normalised.push_back({p[0], p[1], p[2]});
            out.iterates.push_back(to_object(p, o.encoded.frame));
        }
    out.topk_index = r.topk_index;
    out.topk_score = r.topk_score;
    for (int32_t i : r.topk_index) {
        const float* c = &o.candidates[size_t(i) * 3];
        out.topk_point.push_back({c[0], c[1], c[2]});
    }
    out.heatmap = r.heatmap;
    out.alignment = r.alignment;
    return out;
}

Timings timings(VtlocRunner& runner, double wall_ms) {
    Timings t;
    t.wall_ms = wall_ms;
    t.nodes = runner.last_node_times();
    for (auto& [name, ms] : t.nodes) t.gpu_ms += ms;
    return t;
}

}  // namespace

namespace {
const Object::Impl& object_for(const std::shared_ptr<const Object::Impl>& o, const Model::Impl& m) {
    if (!o) throw Error("empty Object (make one with Model::encode_object)");
    if (o->model_key != m.key)
        throw Error("the object was encoded by another model; encode it with " + m.info.path);
    return *o;
}
}  // namespace

std::vector<TouchResult> Model::localize(const Object& object, const std::vector<TactileImage>& images,
                                         const LocalizeOptions& options) {
    return guarded([&] {
        const Object::Impl& o = object_for(object.impl_, *impl_);
        if (images.empty()) throw Error("no tactile images given");
        TouchOptions topt = touch_options(impl_->info, o, options);
        const std::vector<TactileImage> scaled = model_frames(impl_->info, images, options);
        const std::vector<TactileImage>& frames = scaled.empty() ? images : scaled;
        std::lock_guard<std::mutex> lock(impl_->mu);
        VtlocRunner& runner = impl_->runner(options.backend);
        runner.set_profiling(options.profile);
        // One run per image size (a graph has one input shape), in first-seen order.
        std::map<std::pair<int, int>, std::vector<size_t>> groups;
        std::vector<std::pair<int, int>> order;
        for (size_t i = 0; i < frames.size(); ++i) {
            auto key = std::make_pair(frames[i].height, frames[i].width);
            if (!groups.count(key)) order.push_back(key);
            groups[key].push_back(i);
        }
        std::vector<TouchResult> results(images.size());
        for (auto& key : order) {
            std::vector<HostTensor> batch;
            for (size_t i : groups[key]) batch.push_back(image_tensor(frames[i]));
            auto t0 = std::chrono::steady_clock::now();
            std::vector<vtloc::TouchResult> rs = runner.localize(o.encoded, batch, topt);
            Timings t = timings(runner, ms_since(t0));
            for (size_t j = 0; j < rs.size(); ++j) {
                size_t i = groups[key][j];
                results[i] = convert(rs[j], o);
                results[i].timings = t;
                if (options.keep_tensors)
                    results[i].tensors = all_tensors(o, images[i], rs[j], scaled.empty() ? nullptr : &scaled[i]);
            }
        }
        return results;
    });
}

TouchResult Model::localize(const Object& object, const TactileImage& image, const LocalizeOptions& options) {
    return std::move(localize(object, std::vector<TactileImage>{image}, options).at(0));
}


}  // namespace vtloc::api
