// vtloc eval: the model's touches, in batches per object.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <set>

#include <nlohmann/json.hpp>

#include "apps/vtloc/eval.h"

namespace vtloc::cli::eval {

namespace {

constexpr size_t kBatch = 16;  // touches per localize call: one submit, bounded memory

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// What makes the engine build new pipelines: call kind, touch count, candidate count, image size.
std::string shape_key(char kind, const std::vector<api::TactileImage>& images, size_t candidates) {
    char key[96];
    std::snprintf(key, sizeof key, "%c%zu/m%zu/%dx%d", kind, images.size(), candidates, images[0].height,
                  images[0].width);
    return key;
}

// The reason without the leading "path: " the API puts in front.
std::string reason_of(const std::string& message, const std::string& path) {
    const std::string prefix = path + ": ";
    return message.rfind(prefix, 0) == 0 ? message.substr(prefix.size()) : message;
}

// The object cloud --cloud asks for: points.csv with its normals (full), its
// points alone (xyz: normals estimated), or view.xyz with the camera of view.json.
api::Object encode(api::Model& model, const Job& job, const Options& opt) {
    const std::filesystem::path folder(job.rec->folder);
    const HostTensor& p = job.rec->points;
    api::PointCloud cloud;
    std::string source = (folder / "points.csv").string();
    if (opt.cloud == "view") {
        source = (folder / "view.xyz").string();
        cloud = api::load_point_cloud(source, 1);
        const std::string cam_path = (folder / "view.json").string();
        std::ifstream f(cam_path);
        const nlohmann::json cam = nlohmann::json::parse(f, nullptr, false);
        if (cam.is_discarded() || !cam.contains("camera") || !cam["camera"].is_array() || cam["camera"].size() != 3)
            throw api::Error(cam_path + ": missing or without a camera position (run vtloc synth --view)");
        cloud.viewpoint = std::array<double, 3>{cam["camera"][0].get<double>(), cam["camera"][1].get<double>(),
                                                cam["camera"][2].get<double>()};
    } else {
        const size_t n = size_t(p.shape[0]), w = size_t(p.shape[1]);
        for (size_t i = 0; i < n; ++i)
            for (size_t k = 0; k < 3; ++k) {
                cloud.xyz.push_back(p.data[i * w + k]);
                if (opt.cloud == "full") cloud.normals.push_back(w >= 6 ? p.data[i * w + 3 + k] : 0.0f);
            }
    }
    const HostTensor c = job.rec->candidates();
    try {
        return model.encode_object(cloud, c.data, opt.backend);
    } catch (const api::Error& e) {
        throw api::Error(source + ": " + e.what());
    }
}

// Loads touch images by id, once each; a failure is remembered.
class ImageCache {
public:
    ImageCache(const sim::ObjectRecord& o, const Options& opt, std::vector<Skip>& skips)
        : o_(o), opt_(opt), skips_(skips) {}

    // nullptr when the image cannot be read and --skip-bad is on (recorded
    // once in `skips` when `count` is set), else throws.
    const api::TactileImage* get(const sim::TouchRecord& t, bool count) {
        auto it = images_.find(t.id);
        if (it == images_.end()) {
            const std::string path = image_path(o_, t);
            Entry e;
            try {
                e.image = api::load_tactile_image(path);
                e.ok = true;
            } catch (const api::Error& err) {
                if (!opt_.skip_bad) throw;
                e.reason = reason_of(err.what(), path);
                e.path = path;
            }
            it = images_.emplace(t.id, std::move(e)).first;
        }
        Entry& e = it->second;
        if (!e.ok && count && !e.counted) {
            skips_.push_back({o_.name, t.id, e.path, e.reason});
            e.counted = true;
        }
        return e.ok ? &e.image : nullptr;
    }

private:
    struct Entry {
        bool ok = false, counted = false;
        api::TactileImage image;
        std::string path, reason;
    };
    const sim::ObjectRecord& o_;
    const Options& opt_;
    std::vector<Skip>& skips_;
    std::map<int, Entry> images_;
};

// One method's run over every job: the timing (each new shape once untimed), the
// progress line and the rows.
class ModelRun {
public:
    ModelRun(api::Model& model, const Options& opt, std::vector<Skip>& skips, double& engine_ms, size_t total)
        : model_(model), opt_(opt), skips_(skips), engine_ms_(engine_ms),
          progress_("eval " + model.info().name, total) {}

    MethodResult res;

    void job(size_t ji, Job& job) {
        api::LocalizeOptions lo;
        lo.iters = opt_.iters;
        lo.top_k = job.topk;
        lo.gma = false;  // the alignment score is not a metric
        lo.backend = opt_.backend;
        lo.mm_per_px = opt_.frames_mm_per_px;
        ImageCache cache(*job.rec, opt_, skips_);
        api::Object object = encode(model_, job, opt_);
        res.encoded.push_back(object);
        kept_.clear();
        batches(ji, job, object, lo, cache);
        job.touches = kept_;
    }

    void finish() { progress_.finish(); }

private:
    // The first run of a shape compiles its pipelines: run each new shape once
    // untimed, so that the engine time is the steady-state one.
    template <class Call>
    auto timed(const std::string& shape, Call&& call) {
        if (warm_.insert(shape).second) call();
        const auto t0 = Clock::now();
        auto r = call();
        engine_ms_ += ms_since(t0);
        return r;
    }

    void record(size_t ji, const Job& job, const sim::TouchRecord* t, const sim::Point3& pred,
                std::vector<int> ranking, std::vector<float> heat) {
        TouchRow row;
        row.job = ji;
        row.touch = t;
        row.contact = pred;
        // A view cloud is another point set than the dataset's: MPE is then scored on the
        // dataset cloud from the top-K (the same heat-map rule), so every --cloud compares.
        const bool other_points = opt_.cloud == "view";
        row.m = sim::touch_metrics(job.geom, pred, t->contact, std::move(ranking),
                                   other_points ? std::vector<float>{} : heat, job.topk);
        row.heat = std::move(heat);
        res.scores[ji].push_back(sim::score(row.m));
        res.rows.push_back(std::move(row));
        kept_.push_back(t);
    }

    void batches(size_t ji, const Job& job, const api::Object& object, const api::LocalizeOptions& lo,
                 ImageCache& cache) {
        for (size_t b = 0; b < job.touches.size(); b += kBatch) {
            std::vector<const sim::TouchRecord*> batch;
            std::vector<api::TactileImage> images;
            for (size_t i = b; i < std::min(job.touches.size(), b + kBatch); ++i)
                if (const api::TactileImage* im = cache.get(*job.touches[i], true)) {
                    batch.push_back(job.touches[i]);
                    images.push_back(*im);
                }
            if (!batch.empty()) {
                const std::string shape = shape_key('b', images, job.geom.candidates.size());
                std::vector<api::TouchResult> r = timed(shape, [&] { return model_.localize(object, images, lo); });
                for (size_t i = 0; i < batch.size(); ++i)
                    record(ji, job, batch[i], r[i].contact, {}, std::move(r[i].heatmap));
            }
            progress_.advance(std::min(job.touches.size(), b + kBatch) - b);
        }
    }

    api::Model& model_;
    const Options& opt_;
    std::vector<Skip>& skips_;
    double& engine_ms_;
    Progress progress_;
    std::set<std::string> warm_;
    std::vector<const sim::TouchRecord*> kept_;  // the current job's scored touches
};

}  // namespace

MethodResult run_model(api::Model& model, std::vector<Job>& jobs, const Options& opt, std::vector<Skip>& skips,
                       double& engine_ms) {
    size_t total = 0;
    for (const Job& j : jobs) total += j.touches.size();
    engine_ms = 0;
    ModelRun run(model, opt, skips, engine_ms, total);
    run.res.method = model.info().name;
    run.res.scores.resize(jobs.size());
    for (size_t ji = 0; ji < jobs.size(); ++ji) run.job(ji, jobs[ji]);
    run.finish();
    return std::move(run.res);
}

}  // namespace vtloc::cli::eval
