// api::Tracker: the public face of engine/track (the multi-touch filter).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>

#include "base/error.h"
#include "engine/api/api_internal.h"
#include "engine/api/display_sample.h"
#include "engine/api/made_once.h"
#include "engine/io/mesh.h"
#include "engine/io/mesh_formats.h"
#include "engine/io/render.h"
#include "engine/track/codebook.h"
#include "engine/track/pose_shape.h"
#include "engine/track/tracker.h"

namespace vtloc::api {

namespace {

track::Rigid to_rigid(const Motion& m) { return {m.R, m.t}; }
Motion to_motion(const track::Rigid& r) { return {r.R, r.t}; }


track::SurfaceOptions surface_options(const TrackerOptions& o) {
    if (o.n_spin < 1 || o.n_spin > 720) throw Error("tracker: n_spin must be 1..720, got " + std::to_string(o.n_spin));
    if (o.hypotheses < o.n_spin || o.hypotheses > 4000000)
        throw Error("tracker: hypotheses must be n_spin..4,000,000, got " + std::to_string(o.hypotheses));
    track::SurfaceOptions s;
    s.n_spin = o.n_spin;
    s.target_hypotheses = o.hypotheses;
    s.threads = o.threads;
    if (o.candidates.size() > 100000) throw Error("tracker: at most 100,000 candidates, got " + std::to_string(o.candidates.size()));
    for (const auto& c : o.candidates)
        for (double v : c) s.candidates.push_back(float(v));
    return s;
}

track::ScoreOptions score_options(const TrackerOptions& o) {
    return {o.render_weight, o.render_quadratic, o.render_press_percentile, o.render_cell_mm};
}

track::FilterOptions filter_options(const TrackerOptions& o) {
    if (o.window < 1 || o.window > 64) throw Error("tracker: window must be 1..64, got " + std::to_string(o.window));
    if (!(o.network_weight >= 0) || !std::isfinite(o.network_weight)) throw Error("tracker: network_weight must be >= 0");
    if (!(o.render_refined_weight >= 0) || !std::isfinite(o.render_refined_weight))
        throw Error("tracker: render_refined_weight must be >= 0 (0: off)");
    if (std::isnan(o.render_refined_floor) || o.render_refined_floor == INFINITY)
        throw Error("tracker: render_refined_floor must be a number or -inf (none), got " + std::to_string(o.render_refined_floor));
    track::FilterOptions f;
    f.press_mm = o.press_mm;
    f.sigma_d_mm = o.sigma_d_mm;
    f.sigma_a_deg = o.sigma_a_deg;
    f.odometry_mm = o.odometry_mm;
    f.odometry_deg = o.odometry_deg;
    f.online_window = o.window;
    f.mode_radius_mm = o.mode_radius_mm;
    f.grid_allowance = o.grid_allowance;
    f.refine_widen = o.refine_widen;
    if (!(o.refine_widen >= 0)) throw Error("tracker: refine_widen must be >= 0");
    f.refine_reach_mm = o.refine_reach_mm;
    f.rescue_fit = o.rescue_fit;
    f.rescue_modes = o.rescue_modes;
    f.register_rounds = o.register_rounds;
    f.deep_fit = o.deep_fit;
    f.deep_modes = o.deep_modes;
    f.pair_modes = o.pair_modes;
    f.free_space_mm = o.free_space_mm;
    f.free_space_w_mm = o.free_space_w_mm;
    f.free_space_h_mm = o.free_space_h_mm;
    f.threads = o.threads;
    if (o.render_slack_rounds < 0 || o.render_slack_rounds > 8)
        throw Error("tracker: render_slack_rounds must be 0..8 (0: off), got " + std::to_string(o.render_slack_rounds));
    f.shape_slack_rounds = o.render_slack_rounds;
    f.field_slack = o.field_slack;
    if (!(o.grid_allowance >= 0) || !(o.sigma_d_mm > 0) || !(o.sigma_a_deg > 0) || !std::isfinite(o.press_mm))
        throw Error("tracker: widths must be > 0, grid_allowance >= 0 and press_mm finite");
    f.term_weight = 1;  // the network's temperature is applied when its field is made
    return f;
}

}  // namespace

struct Tracker::Impl {
    rt::Context* ctx;
    track::Tracker tracker;
    // The display cloud and its rows for Tracker::heatmap: read-only, shared by with_options' trackers.
    struct Display {
        PointCloud cloud;
        HostTensor rows;
    };
    std::shared_ptr<const Display> display;
    TrackerOptions options;  // as made (with_options compares what shapes the surface)
    double object_units;     // options' for a file; 1 for a PointCloud, given in the tracker's units
    track::ScoreOptions score;  // render-and-compare's, checked with the others (check_options): the scorer is made at the first gel shape
    // The object's codebook on the device, made at the first gel shape of any tracker sharing
    // it: with_options' trackers share it unless they name another codebook_cache, whose file
    // must then be read (and checked) or written. Scores with each tracker's own options.
    struct Book {
        std::string cache;  // the codebook_cache it is read from or written to
        MadeOnce<track::CodebookScorer> scorer;
    };
    std::shared_ptr<Book> book;
    // Render-and-compare at the refined poses (render_refined_weight > 0): the dense points binned,
    // made at the first gel shape of any tracker sharing it (with_options' all do: it hangs on
    // the surface alone).
    std::shared_ptr<MadeOnce<const track::PoseShapeScorer>> pose_shapes;
    // The tracker's calls run one at a time (Python releases the GIL in add_touch, so one thread
    // may read the estimate while another adds a touch); with_options holds its source's.
    mutable std::mutex mu;
    Impl(rt::Context& c, track::Surface s, const TrackerOptions& o, PointCloud disp)
        : ctx(&c), tracker(c, std::move(s), filter_options(o)), options(o), object_units(o.object_units), score(score_options(o)),
          book(std::make_shared<Book>()), pose_shapes(std::make_shared<MadeOnce<const track::PoseShapeScorer>>()) {
        book->cache = o.codebook_cache;
        tracker.profile_steps(o.profile);
        // With normals, a thin part's two faces each show their own belief (Tracker::heatmap).
        const bool n = disp.normals.size() == disp.xyz.size();
        std::vector<float> rows;
        for (size_t i = 0; i < disp.size(); ++i) {
            rows.insert(rows.end(), &disp.xyz[3 * i], &disp.xyz[3 * i + 3]);
            if (n) rows.insert(rows.end(), &disp.normals[3 * i], &disp.normals[3 * i + 3]);
        }
        const int64_t count = int64_t(disp.size());
        display = std::make_shared<const Display>(Display{std::move(disp), HostTensor({count, n ? 6 : 3}, std::move(rows))});
    }
    // `like`'s object under other options (with_options): its surface, tables, display, pose
    // scorer and codebook (the same cache) shared, not copied or made again.
    Impl(const Impl& like, const TrackerOptions& o)
        : ctx(like.ctx), tracker(like.tracker, filter_options(o)), display(like.display), options(o), object_units(like.object_units),
          score(score_options(o)), pose_shapes(like.pose_shapes) {
        if (o.codebook_cache.empty() || o.codebook_cache == like.book->cache) {
            book = like.book;
        } else {
            book = std::make_shared<Book>();
            book->cache = o.codebook_cache;
        }
        tracker.profile_steps(o.profile);
    }

    static void check_shape(const GelShape& g, size_t touch) {
        if (g.height < 1 || g.width < 1 || g.depth_mm.size() != size_t(g.height) * size_t(g.width))
            throw Error("touch " + std::to_string(touch) + ": its gel shape has " + std::to_string(g.depth_mm.size()) + " heights for " +
                        std::to_string(g.height) + " x " + std::to_string(g.width) + " pixels");
    }

    // Render-and-compare's term for one touch's gel shape (SPEC 9), or none.
    std::vector<float> shape_field(const GelShape* g, size_t touch) {
        if (!g) return {};
        check_shape(*g, touch);
        const std::shared_ptr<track::CodebookScorer> scorer = book->scorer.get([&] {
            const track::Codebook b = track::cached_codebook(ctx, tracker.surface(), {}, book->cache);
            return std::make_shared<track::CodebookScorer>(ctx, b, tracker.surface(), score);
        });
        // The gel's millimetres are the robot's; the surface is in the tracker's units (object_units applied).
        return scorer->term(g->depth_mm, g->height, g->width, g->mm_per_px, score);
    }

    // Render-and-compare at the refined poses for one touch's gel shape, or none.
    track::PoseTerm pose_term(const GelShape* g, size_t touch) {
        if (!g || !(options.render_refined_weight > 0)) return {};
        check_shape(*g, touch);
        const std::shared_ptr<const track::PoseShapeScorer> sc =
            pose_shapes->get([&] { return std::make_shared<const track::PoseShapeScorer>(tracker.surface()); });
        auto win = std::make_shared<const track::ShapeWindow>(track::shape_window(g->depth_mm, g->height, g->width, g->mm_per_px, score));
        return [sc, win, w = options.render_refined_weight, q = score.quadratic,
                f = options.render_refined_floor](const track::Rigid& x) {
            return sc->score(x, *win, w, q, f);
        };
    }
    std::vector<track::PoseTerm> pose_terms(const std::vector<const GelShape*>& shapes) {
        std::vector<track::PoseTerm> t;
        for (size_t i = 0; i < shapes.size(); ++i) t.push_back(pose_term(shapes[i], i + 1));
        return t;
    }

    // Every term a touch has, summed (log fields multiply).
    std::vector<float> touch_field(const TouchResult* r, const Object* object, const GelShape* g, size_t touch) {
        std::vector<float> f = network_field(r, object, touch), h = shape_field(g, touch);
        if (f.empty()) return h;
        for (size_t i = 0; i < h.size(); ++i) f[i] += h[i];
        return f;
    }

    // The network's heat-map over `object`'s cloud as a log field over the
    // hypotheses: each sample takes its nearest cloud point's heat h, log(h + 0.05)
    // (a floor: one wrong heat-map cannot veto what the geometry says).
    std::vector<float> network_field(const TouchResult* r, const Object* object, size_t touch) const {
        if (!r) return {};
        if (!object) throw Error("touch " + std::to_string(touch) + ": a network result needs the Object it was computed on");
        // The Object holds the file's units; the tracker's surface is scaled by object_units.
        std::vector<float> xyz = object->cloud().xyz;
        for (float& v : xyz) v = float(v * object_units);
        const size_t N = xyz.size() / 3;
        if (r->heatmap.size() != N)
            throw Error("touch " + std::to_string(touch) + ": the result's heat-map has " + std::to_string(r->heatmap.size()) +
                        " values for the object's " + std::to_string(N) + " points");
        const track::Surface& s = tracker.surface();
        const int64_t S = s.n_samples(), NS = s.n_spin();
        std::vector<float> f(size_t(S * NS));
        for (int64_t i = 0; i < S; ++i) {
            const float* p = &s.samples[size_t(9 * i)];
            size_t best = 0;
            float bd = INFINITY;
            for (size_t j = 0; j < N; ++j) {
                const float d = (xyz[3 * j] - p[0]) * (xyz[3 * j] - p[0]) + (xyz[3 * j + 1] - p[1]) * (xyz[3 * j + 1] - p[1]) +
                                (xyz[3 * j + 2] - p[2]) * (xyz[3 * j + 2] - p[2]);
                if (d < bd) bd = d, best = j;
            }
            const float v = float(options.network_weight * std::log(double(r->heatmap[best]) + 0.05));
            std::fill(f.begin() + i * NS, f.begin() + (i + 1) * NS, v);
        }
        return f;
    }

    TrackerEstimate convert(const track::Estimate& e, int touches) const {
        TrackerEstimate o;
        o.touches = touches;
        o.contact = e.contact;
        o.pose = to_motion(e.pose);
        o.pose_contact = e.pose_contact;
        for (const auto& w : e.window_poses) o.window_poses.push_back(to_motion(w));
        for (const auto& m : e.modes) o.modes.push_back({m.contact, m.probability});
        o.mass_within_5mm = e.mass_within_5mm;
        o.fit = e.fit;
        o.pose_terms = e.pose_terms;
        o.heatmap = tracker.heatmap(e, display->rows);
        o.sample_belief = e.sample_belief;
        return o;
    }
};

Motion compose(const Motion& a, const Motion& b) { return to_motion(track::compose(to_rigid(a), to_rigid(b))); }
Motion inverse(const Motion& a) { return to_motion(track::inverse(to_rigid(a))); }

std::vector<Motion> motions_from_flange_poses(const std::vector<Motion>& flange, const Motion& tool) {
    return guarded([&] {
        track::check_rigid(to_rigid(tool), "the tool (flange-to-sensor) transform");
        std::vector<Motion> out;
        for (size_t k = 0; k < flange.size(); ++k) {
            track::check_rigid(to_rigid(flange[k]), "flange pose " + std::to_string(k + 1));
            if (k) out.push_back(to_motion(sensor_motion(to_rigid(flange[k - 1]), to_rigid(flange[k]), to_rigid(tool))));
        }
        return out;
    });
}

namespace {

// Every option, before the object is read and its surface built (seconds on a big mesh).
void check_options(const TrackerOptions& o) {
    if (!(o.object_units > 0) || !std::isfinite(o.object_units)) throw Error("tracker: object_units must be a finite number > 0");
    surface_options(o);
    track::Tracker::check_options(filter_options(o));
    track::check_score_options(score_options(o));
}

}  // namespace

Tracker::Tracker(Context& context, const std::string& path, const TrackerOptions& o) {
    guarded([&] {
        check_options(o);
        PointCloud cloud;
        try {
            io::TriangleMesh mesh = io::load_mesh(path);
            for (float& v : mesh.positions) v = float(v * o.object_units);
            io::orient_outward(mesh);  // a pose presses against the outward normal: an inward-wound file would veto every true pose
            HostTensor dense = io::tracker_dense_sample(mesh, path);
            HostTensor disp = display_sample(mesh, 4096, path);  // evenly spaced: a picture without holes
            PointCloud d;
            for (int64_t i = 0; i < disp.shape[0]; ++i)
                for (int k = 0; k < 3; ++k) d.xyz.push_back(disp.data[size_t(6 * i + k)]), d.normals.push_back(disp.data[size_t(6 * i + 3 + k)]);
            impl_ = std::make_unique<Impl>(ContextAccess::rt(context), track::build_surface(dense, true, surface_options(o), path), o, d);
            return;
        } catch (const ::vtloc::Error& e) {
            // Not a mesh with faces: read it as a point cloud (below), unless the file is unreadable.
            const std::string why = e.what();
            if (why.find("no faces") == std::string::npos && why.find("unknown mesh extension") == std::string::npos) throw;
        }
        cloud = load_point_cloud(path, 1);
        for (float& v : cloud.xyz) v = float(v * o.object_units);
        *this = Tracker(context, cloud, o);
        impl_->object_units = o.object_units;
    });
}

Tracker::Tracker(Context& context, const PointCloud& cloud, const TrackerOptions& o) {
    guarded([&] {
        check_options(o);
        if (cloud.normals.size() != cloud.xyz.size())
            throw Error("tracker: the cloud needs a normal per point (the filter checks each pose against the surface's normal)");
        HostTensor t = cloud_tensor(cloud);
        impl_ = std::make_unique<Impl>(ContextAccess::rt(context), track::build_surface(t, false, surface_options(o), "cloud"), o, cloud);
        impl_->object_units = 1;  // a PointCloud is given in the tracker's units
    });
}

Tracker::Tracker(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

namespace {
std::unique_lock<std::mutex> one_at_a_time(const Tracker::Impl& t) { return std::unique_lock<std::mutex>(t.mu); }
}  // namespace

Tracker Tracker::with_options(const TrackerOptions& o) const {
    return guarded([&] {
        check_options(o);
        const TrackerOptions& mine = impl_->options;
        auto same = [](const char* name, bool equal) {
            if (!equal)
                throw Error(std::string("tracker: with_options keeps the object's surface, so ") + name +
                            " must be this tracker's (make a new Tracker to change it)");
        };
        same("n_spin", o.n_spin == mine.n_spin);
        same("hypotheses", o.hypotheses == mine.hypotheses);
        same("candidates", o.candidates == mine.candidates);
        same("object_units", o.object_units == mine.object_units);
        const auto lock = one_at_a_time(*impl_);
        return Tracker(std::make_unique<Impl>(*impl_, o));  // object_units as this tracker's (1 for a PointCloud's)
    });
}

const TrackerOptions& Tracker::options() const { return impl_->options; }

Tracker::~Tracker() = default;
Tracker::Tracker(Tracker&&) noexcept = default;
Tracker& Tracker::operator=(Tracker&&) noexcept = default;

void Tracker::add_touch(const std::optional<Motion>& motion, const TouchResult* network, const Object* object, const GelShape* shape) {
    guarded([&] {
        const auto lock = one_at_a_time(*impl_);
        const size_t n = size_t(impl_->tracker.touches() + 1);
        std::vector<float> f = impl_->touch_field(network, object, shape, n);
        impl_->tracker.add_touch(motion ? std::optional<track::Rigid>(to_rigid(*motion)) : std::nullopt, f, impl_->pose_term(shape, n));
    });
}

void Tracker::add_touch_term(const std::optional<Motion>& motion, const std::vector<float>& term, const GelShape* shape) {
    guarded([&] {
        const auto lock = one_at_a_time(*impl_);
        track::PoseTerm p = impl_->pose_term(shape, size_t(impl_->tracker.touches() + 1));
        impl_->tracker.add_touch(motion ? std::optional<track::Rigid>(to_rigid(*motion)) : std::nullopt, term, std::move(p));
    });
}

double Tracker::max_hop() const { return impl_->tracker.max_hop_mm(); }

void Tracker::check_motion(const Motion& motion, int touch) const {
    guarded([&] {
        if (touch < 2) throw Error("check_motion: touch " + std::to_string(touch) + " has no motion (the first is touch 1)");
        impl_->tracker.check_motion(to_rigid(motion), size_t(touch));
    });
}

int Tracker::touches() const {
    const auto lock = one_at_a_time(*impl_);
    return impl_->tracker.touches();
}

void Tracker::reset() {
    const auto lock = one_at_a_time(*impl_);
    impl_->tracker.reset();
}

TrackerEstimate Tracker::estimate() const {
    return guarded([&] {
        const auto lock = one_at_a_time(*impl_);
        return impl_->convert(impl_->tracker.estimate(), impl_->tracker.touches());
    });
}

TrackerEstimate Tracker::evaluate_window(const std::vector<Motion>& motions, const std::vector<const TouchResult*>& network,
                                         const Object* object, const std::vector<const GelShape*>& shapes) {
    return guarded([&] {
        const auto lock = one_at_a_time(*impl_);
        std::vector<track::Rigid> m;
        for (const Motion& x : motions) m.push_back(to_rigid(x));
        const size_t W = motions.size() + 1;
        if (!network.empty() && network.size() != W)
            throw Error("window: " + std::to_string(network.size()) + " network results for " + std::to_string(W) + " touches");
        if (!shapes.empty() && shapes.size() != W)
            throw Error("window: " + std::to_string(shapes.size()) + " gel shapes for " + std::to_string(W) + " touches");
        std::vector<std::vector<float>> terms;
        bool any = false;
        for (size_t i = 0; i < W; ++i) {
            const TouchResult* r = network.empty() ? nullptr : network[i];
            const GelShape* g = shapes.empty() ? nullptr : shapes[i];
            terms.push_back(impl_->touch_field(r, object, g, i + 1));
            any = any || r || g;
        }
        if (!any) terms.clear();
        return impl_->convert(impl_->tracker.evaluate_window(m, terms, impl_->pose_terms(shapes)), int(motions.size() + 1));
    });
}

std::vector<float> Tracker::touch_term(const TouchResult* network, const Object* object, const GelShape* shape) {
    return guarded([&] {
        const auto lock = one_at_a_time(*impl_);
        return impl_->touch_field(network, object, shape, 1);
    });
}

TrackerEstimate Tracker::evaluate_window_terms(const std::vector<Motion>& motions, const std::vector<std::vector<float>>& terms,
                                               const std::vector<const GelShape*>& shapes) {
    return guarded([&] {
        const auto lock = one_at_a_time(*impl_);
        std::vector<track::Rigid> m;
        for (const Motion& x : motions) m.push_back(to_rigid(x));
        if (!terms.empty() && terms.size() != motions.size() + 1)
            throw Error("window: " + std::to_string(terms.size()) + " touch terms for " + std::to_string(motions.size() + 1) + " touches");
        if (!shapes.empty() && shapes.size() != motions.size() + 1)
            throw Error("window: " + std::to_string(shapes.size()) + " gel shapes for " + std::to_string(motions.size() + 1) + " touches");
        const bool any = std::any_of(terms.begin(), terms.end(), [](const std::vector<float>& t) { return !t.empty(); });
        return impl_->convert(impl_->tracker.evaluate_window(m, any ? terms : std::vector<std::vector<float>>{}, impl_->pose_terms(shapes)),
                              int(motions.size() + 1));
    });
}

std::vector<float> Tracker::shape_term(const GelShape& shape) {
    return guarded([&] {
        const auto lock = one_at_a_time(*impl_);
        return impl_->shape_field(&shape, 1);
    });
}

double Tracker::window_fit(const std::vector<Motion>& motions, const Motion& pose) const {
    return guarded([&] {
        const auto lock = one_at_a_time(*impl_);
        std::vector<track::Rigid> m;
        for (const Motion& x : motions) m.push_back(to_rigid(x));
        return impl_->tracker.window_fit(m, to_rigid(pose));
    });
}

std::vector<float> Tracker::belief() const {
    const auto lock = one_at_a_time(*impl_);
    return impl_->tracker.belief();
}

std::vector<float> Tracker::sample_points() const {
    const track::Surface& s = impl_->tracker.surface();
    std::vector<float> p;
    for (int64_t i = 0; i < s.n_samples(); ++i) p.insert(p.end(), &s.samples[size_t(9 * i)], &s.samples[size_t(9 * i + 3)]);
    return p;
}

int Tracker::n_spin() const { return impl_->tracker.surface().n_spin(); }
const PointCloud& Tracker::display_cloud() const { return impl_->display->cloud; }
uint64_t Tracker::device_bytes() const {
    const auto lock = one_at_a_time(*impl_);
    const std::shared_ptr<track::CodebookScorer> scorer = impl_->book->scorer.peek();
    return impl_->tracker.device_bytes() + (scorer ? scorer->device_bytes() : 0);
}
uint64_t Tracker::host_bytes() const {
    const auto lock = one_at_a_time(*impl_);
    const Impl::Display& d = *impl_->display;
    const std::shared_ptr<const track::PoseShapeScorer> pose = impl_->pose_shapes->peek();
    return impl_->tracker.host_bytes() + 4 * uint64_t(d.cloud.xyz.size() + d.cloud.normals.size() + d.rows.data.size()) +
           (pose ? pose->bytes() : 0);
}
double Tracker::spacing_mm() const { return impl_->tracker.surface().spacing_mm; }
track::Tracker& TrackerAccess::core(Tracker& t) { return t.impl_->tracker; }
TrackerAccess::ShapeScorers TrackerAccess::shape_scorers(Tracker& t) {
    const auto lock = one_at_a_time(*t.impl_);
    const Tracker::Impl& i = *t.impl_;
    auto b = std::make_shared<const track::Codebook>(track::cached_codebook(i.ctx, i.tracker.surface(), {}, i.book->cache));
    return {b, std::make_shared<track::CodebookScorer>(i.ctx, *b, i.tracker.surface(), i.score),
            std::make_shared<track::CodebookScorer>(nullptr, *b, i.tracker.surface(), i.score)};
}
std::vector<float> TrackerAccess::shape_term(Tracker& t, track::CodebookScorer& scorer, const GelShape& g) {
    const auto lock = one_at_a_time(*t.impl_);
    Tracker::Impl::check_shape(g, 1);
    return scorer.term(g.depth_mm, g.height, g.width, g.mm_per_px, t.impl_->score);
}
std::vector<std::pair<std::string, double>> Tracker::step_nodes() const {
    const auto lock = one_at_a_time(*impl_);
    return impl_->tracker.step_node_times();
}

void render_tracker_png(const std::string& path, const Tracker& tracker, const std::vector<TrackerEstimate>& steps,
                        const std::vector<std::string>& captions, const std::vector<std::array<double, 3>>& truths) {
    guarded([&] {
        if (steps.empty()) throw Error(path + ": no estimate to draw");
        const PointCloud& c = tracker.display_cloud();
        if (c.normals.size() != c.xyz.size()) throw Error(path + ": the display cloud has no normals");
        HostTensor cloud({int64_t(c.size()), 6});
        for (size_t i = 0; i < c.size(); ++i)
            for (int k = 0; k < 3; ++k) cloud.data[6 * i + size_t(k)] = c.xyz[3 * i + size_t(k)], cloud.data[6 * i + 3 + size_t(k)] = c.normals[3 * i + size_t(k)];
        const int cols = std::min<int>(4, int(steps.size())), rows = (int(steps.size()) + cols - 1) / cols;
        const int W = 640, H = 400;
        io::RgbImage sheet(rows * H, cols * W);
        for (size_t k = 0; k < steps.size(); ++k) {
            io::RenderOptions ro;
            ro.width = W, ro.height = H;
            ro.contact = std::array<float, 3>{float(steps[k].contact[0]), float(steps[k].contact[1]), float(steps[k].contact[2])};
            if (k < truths.size()) ro.ground_truth = std::array<float, 3>{float(truths[k][0]), float(truths[k][1]), float(truths[k][2])};
            ro.caption = k < captions.size() ? captions[k] : "after touch " + std::to_string(steps[k].touches);
            if (steps[k].heatmap.size() != c.size()) throw Error(path + ": estimate " + std::to_string(k + 1) + " has no heat-map for the display cloud");
            const io::RgbImage panel = io::render_heatmap(cloud, steps[k].heatmap, ro);
            const int r0 = int(k) / cols * H, c0 = int(k) % cols * W;
            for (int y = 0; y < H; ++y)
                std::memcpy(&sheet.pixels[(size_t(r0 + y) * size_t(cols * W) + size_t(c0)) * 3], &panel.pixels[size_t(y) * W * 3], size_t(W) * 3);
        }
        io::save_png(path, sheet);
    });
}

}  // namespace vtloc::api
