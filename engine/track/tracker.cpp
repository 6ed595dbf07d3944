#include "engine/track/tracker.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <functional>
#include <map>
#include <numeric>
#include <thread>

#include "base/error.h"
#include "engine/executor.h"
#include "engine/ops/build.h"
#include "engine/ops/pose_evidence.h"
#include "engine/resident_weights.h"
#include "engine/track/nearest_facing.h"
#include "engine/track/pair_search.h"
#include "engine/parallel.h"
#include "engine/track/registration.h"
#include "engine/track/window_fit.h"
#include "engine/weights.h"

namespace vtloc::track {

namespace {


using P = ops::pose::V3;
constexpr int64_t kMaxAnswers = 512;
bool slack_on(const FilterOptions& o) { return o.field_slack && (o.odometry_mm > 0 || o.odometry_deg > 0); }
// The refinement registers onto the dense points; a candidate keeps its place.
bool registers(const FilterOptions& o, const Surface& s) { return o.register_rounds > 0 && !s.from_candidates; }
// The pair search seeds the deep search, which registers.
bool pairs_on(const FilterOptions& o, const Surface& s) { return registers(o, s) && o.deep_modes > 0 && o.pair_modes > 0; }

// A search index over the surface's dense points, made on first use; it keeps the surface alive.
template <class Index>
std::shared_ptr<const LazyIndex<Index>> lazy_index(const std::shared_ptr<const Surface>& s) {
    return std::make_shared<const LazyIndex<Index>>(std::shared_ptr<const std::vector<float>>(s, &s->dense));
}

int64_t answer_stride(const Surface& s) { return std::max<int64_t>(1, (s.n_samples() + kMaxAnswers - 1) / kMaxAnswers); }

}  // namespace

struct Tracker::Impl {
    rt::Context* ctx;  // null: the ops' CPU references run the step
    WeightStore weights;
    std::shared_ptr<ResidentWeights> resident;
    std::map<std::pair<int64_t, int64_t>, std::unique_ptr<GpuExecutor>> exec;  // by (K terms, F fields)
    std::map<std::pair<int64_t, int64_t>, Graph> graphs;                       // the CPU reference's
    std::shared_ptr<const LazyNearestFacing> nearest;  // the refinement's registration (null: off); with_options' trackers share it
    std::shared_ptr<const LazyPairIndex> pairs;    // the deep search's pair search (null: off); shared likewise
    bool profile = false;                          // profile_steps
    std::optional<std::pair<int64_t, int64_t>> last_exec;  // the last step's executor (its node times, while profiling)
    bool capture = false;                          // capture_steps
    // The last step's inputs, while capturing; its graph is built when last_step_case() asks
    // (graph_of: its K, F and term field), not at every step.
    mutable std::optional<StepCase> last_case;
    mutable std::optional<std::array<int64_t, 3>> graph_of;
    explicit Impl(rt::Context* c) : ctx(c), resident(c ? std::make_shared<ResidentWeights>(*c) : nullptr) {}
};

Tracker::Tracker(rt::Context& ctx, Surface surface, FilterOptions options) : Tracker(&ctx, std::move(surface), options) {}

void Tracker::check_options(const FilterOptions& opt_) {
    if (!(opt_.mode_radius_mm > 0) || !std::isfinite(opt_.mode_radius_mm))
        throw Error("filter options: mode_radius_mm must be positive and finite, got " + std::to_string(opt_.mode_radius_mm));
    if (!(opt_.sigma_d_mm > 0) || !(opt_.sigma_a_deg > 0) || !(opt_.odometry_mm >= 0) || !(opt_.odometry_deg >= 0) ||
        !(opt_.odometry_mm <= 1e6) || !(opt_.odometry_deg <= 1e6) || !std::isfinite(opt_.sigma_d_mm) || !std::isfinite(opt_.sigma_a_deg) ||
        !std::isfinite(opt_.press_mm) || opt_.n_modes < 1 || opt_.refine < 0)
        throw Error("filter options: widths must be positive and finite, odometry noise finite and >= 0 (at most 1e6), n_modes >= 1");
    if (opt_.threads < 0 || opt_.threads > 256)
        throw Error("filter options: threads must be 0 (up to 4) or 1..256, got " + std::to_string(opt_.threads));
    if (!(opt_.refine_reach_mm >= 0))
        throw Error("filter options: refine_reach_mm must be >= 0 (0: off), got " + std::to_string(opt_.refine_reach_mm));
    if (opt_.register_rounds < 0 || opt_.register_rounds > 64 || !(opt_.register_scale >= 1) || !(opt_.register_scale <= 1e3))
        throw Error("filter options: register_rounds must be 0..64 (0: off) and register_scale 1..1000, got " +
                    std::to_string(opt_.register_rounds) + " and " + std::to_string(opt_.register_scale));
    if (!(opt_.free_space_mm >= 0) || !(opt_.free_space_w_mm > 0) || !(opt_.free_space_h_mm > 0))
        throw Error("filter options: free_space_mm must be >= 0 (0: off) and the pad's size positive");
    if (opt_.shape_climb_rounds < 0 || opt_.shape_climb_rounds > 8 || opt_.shape_climb_modes < 0 || opt_.shape_climb_modes > 256)
        throw Error("filter options: shape_climb_rounds must be 0..8 and shape_climb_modes 0..256, got " +
                    std::to_string(opt_.shape_climb_rounds) + " and " + std::to_string(opt_.shape_climb_modes));
    if (opt_.shape_slack_rounds < 0 || opt_.shape_slack_rounds > 8)
        throw Error("filter options: shape_slack_rounds must be 0..8, got " + std::to_string(opt_.shape_slack_rounds));
    if (std::isnan(opt_.deep_fit) || opt_.deep_modes < 0 || opt_.deep_modes > 64 || !(opt_.register_cap >= 0) || !std::isfinite(opt_.register_cap))
        throw Error("filter options: deep_fit must not be NaN, deep_modes must be 0..64 (0: off) and register_cap finite and >= 0 (0: no cap), got " +
                    std::to_string(opt_.deep_modes) + " and " + std::to_string(opt_.register_cap));
    if (opt_.pair_modes < 0 || opt_.pair_modes > 64)
        throw Error("filter options: pair_modes must be 0..64 (0: off), got " + std::to_string(opt_.pair_modes));
    if (std::isnan(opt_.rescue_fit) || opt_.rescue_modes < 0 || opt_.rescue_modes > 256)
        throw Error("filter options: rescue_fit must not be NaN and rescue_modes must be 0..256, got " +
                    std::to_string(opt_.rescue_modes));
}

Tracker::Tracker(rt::Context* ctx, Surface surface, FilterOptions options)
    : surface_(std::make_shared<const Surface>(std::move(surface))), opt_(options), impl_(std::make_unique<Impl>(ctx)) {
    check_options(opt_);
    if (registers(opt_, *surface_)) impl_->nearest = lazy_index<NearestFacing>(surface_);
    if (pairs_on(opt_, *surface_)) impl_->pairs = lazy_index<PairIndex>(surface_);
    add_tables();
}

Tracker::Tracker(const Tracker& like, FilterOptions options)
    : surface_(like.surface_), opt_(options), impl_(std::make_unique<Impl>(like.impl_->ctx)) {
    check_options(opt_);
    // The surface, its tree and its tables are read-only once made: shared with `like`, not
    // copied (the weight store's tensors are shared too). The tree and the pair index (each made
    // on first use) are set up where these options need them and `like`'s did not, the
    // neighbours likewise.
    if (registers(opt_, *surface_))
        impl_->nearest = like.impl_->nearest ? like.impl_->nearest : lazy_index<NearestFacing>(surface_);
    if (pairs_on(opt_, *surface_)) impl_->pairs = like.impl_->pairs ? like.impl_->pairs : lazy_index<PairIndex>(surface_);
    impl_->weights = like.impl_->weights;
    if (slack_on(opt_) && !impl_->weights.has("surface.neighbours")) add_neighbours();
    // Their device copies too: every table is the surface's alone, whatever the options, so
    // the trackers of one object hold them once (a failed build gives back only what no other
    // executor reads: ResidentWeights::forget).
    impl_->resident = like.impl_->resident;
}

Tracker Tracker::cpu_reference_of(const Tracker& like) {
    Tracker t(like, like.opt_);
    t.impl_->ctx = nullptr;
    t.impl_->resident = nullptr;
    return t;
}

Tracker::Tracker(Tracker&&) noexcept = default;

void Tracker::add_neighbours() {
    impl_->weights.add("surface.neighbours", slack_neighbours(*surface_, kSlackNeighbours, slack_radius(*surface_)));
}

void Tracker::add_tables() {
    const Surface& s = *surface_;
    WeightStore& w = impl_->weights;
    w.add("surface.samples", HostTensor({s.n_samples(), 12}, ops::pose::evidence_samples(s.samples)));
    w.add("surface.dense", HostTensor({s.n_dense(), 8}, ops::pose::evidence_dense(s.dense, s.dense_sample)));
    w.add("surface.cells", HostTensor::from_ints({s.n_cells(), 2}, s.cells));
    w.add("surface.spins", HostTensor({int64_t(s.n_spin()), 2}, s.spins));
    std::vector<float> pts;
    for (int64_t i = 0; i < s.n_samples(); ++i) pts.insert(pts.end(), &s.samples[size_t(i * 9)], &s.samples[size_t(i * 9 + 3)]);
    w.add("surface.points", HostTensor({s.n_samples(), 3}, pts));
    // The GPU's Bayes risk is asked of every answer_stride-th sample (at most
    // kMaxAnswers): the risk is smooth, and the host adds the best-held samples.
    std::vector<float> ans;
    for (int64_t i = 0; i < s.n_samples(); i += answer_stride(s)) ans.insert(ans.end(), &pts[size_t(3 * i)], &pts[size_t(3 * i + 3)]);
    w.add("surface.answers", HostTensor({int64_t(ans.size() / 3), 3}, ans));
    if (slack_on(opt_)) add_neighbours();
}

Tracker::~Tracker() = default;

namespace {

// One filter step's graph: evidence over K terms and F fields, then the belief,
// its spin marginal and the Bayes risk of each sample.
Graph step_graph(const Surface& s, const FilterOptions& o, int64_t K, int64_t F, int64_t own) {
    Graph g;
    const int64_t S = s.n_samples(), NS = s.n_spin(), H = S * NS;
    ops::PoseEvidence p;
    p.press = o.press_mm;
    p.log_floor = o.log_floor;
    p.field_floor = -30;
    for (int k = 0; k < 3; ++k) p.origin[k] = s.origin[size_t(k)], p.dims[k] = s.dims[size_t(k)];
    p.voxel = s.voxel;
    p.own_field = own;
    p.own_weight = 1;
    int fields = g.input("fields", {F, H});
    if (slack_on(o) && F > 0)
        fields = ops::field_slack(g, fields, g.weight("surface.neighbours", {S, kSlackNeighbours, 3}), g.input("widths", {F, 2}),
                                  NS, "track.slack");
    int score = ops::pose_evidence(g, g.weight("surface.samples", {S, 12}), g.weight("surface.dense", {s.n_dense(), 8}),
                                   g.weight("surface.cells", {s.n_cells(), 2}, ElemType::I32),
                                   g.weight("surface.spins", {NS, 2}), g.input("terms", {K, 16}), fields, p,
                                   "track.evidence");
    std::vector<int> lp = ops::log_softmax(g, score, "track.belief");
    int m = ops::spin_marginal(g, lp[1], NS, "track.marginal");
    const int64_t A = (S + answer_stride(s) - 1) / answer_stride(s);
    int c = ops::expected_distance(g, g.weight("surface.points", {S, 3}), m, g.weight("surface.answers", {A, 3}), "track.risk");
    g.output(lp[0], "log");
    g.output(lp[1], "prob");
    g.output(m, "marginal");
    g.output(c, "cost");
    return g;
}

Rigid rigid_of(const ops::pose::Frame& f) {
    Rigid r;
    r.R = {f.x.x, f.y.x, f.z.x, f.x.y, f.y.y, f.z.y, f.x.z, f.y.z, f.z.z};
    r.t = {f.t.x, f.t.y, f.t.z};
    return r;
}

// A small rotation about the pose's own axes (Rodrigues) and a shift in its frame; with a
// pivot (a world point), the rotation turns about the pivot instead of the pose's origin.
Rigid perturb(const Rigid& x, const double d[6], const std::array<double, 3>* pivot = nullptr) {
    Rigid m;
    m.R = rotation_of(d);
    m.t = {d[3], d[4], d[5]};
    if (pivot) {  // the pivot, in the pose's frame, is where m leaves it: m.t += c - m.R c
        std::array<double, 3> c{};
        for (size_t i = 0; i < 3; ++i)
            for (size_t j = 0; j < 3; ++j) c[i] += x.R[j * 3 + i] * ((*pivot)[j] - x.t[j]);
        for (size_t i = 0; i < 3; ++i) m.t[i] += c[i] - (m.R[i * 3] * c[0] + m.R[i * 3 + 1] * c[1] + m.R[i * 3 + 2] * c[2]);
    }
    return compose(x, m);
}

// Where a pose's axis meets the surface: the tangent plane of the dense point it
// presses (the pose's own press back along its axis where no point is near).
std::array<double, 3> axis_contact(const Surface& s, const ops::pose::Grid& grid, const Rigid& x, double press) {
    const ops::pose::Frame f = frame_of(x);
    std::array<double, 3> c{f.t.x - press * f.z.x, f.t.y - press * f.z.y, f.t.z - press * f.z.z};
    const int32_t i = ops::pose::pressed_point(grid, ops::pose::cell_of(grid, f.t), f.z);
    if (i >= 0) {
        const float* q = &s.dense[size_t(6 * i)];
        const P n{q[3], q[4], q[5]};
        const float dz = ops::pose::dot(f.z, n);
        if (std::abs(dz) > 1e-3f) {
            const float lam = ops::pose::dot(ops::pose::sub(P{q[0], q[1], q[2]}, f.t), n) / dz;
            c = {f.t.x + lam * f.z.x, f.t.y + lam * f.z.y, f.t.z + lam * f.z.z};
        }
    }
    return c;
}

// FilterOptions::free_space_mm: a 5 x 4 grid of pad points that far behind the gel plane; each
// one the grid finds inside the object (behind its nearest dense point's tangent plane) costs
// the robust Gaussian of that depth, zero when outside. Points the grid holds nothing for (far
// from the surface, or off the grid) cost nothing: the band is a few millimetres wide.
double free_space_log(const ops::pose::Grid& g, const ops::pose::Frame& f, const FilterOptions& o) {
    using namespace ops::pose;
    const float floor = float(o.log_floor), s = float(o.sigma_d_mm);
    const float exp_floor = std::exp(floor), zero = robust_log(0, exp_floor);
    double v = 0;
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 4; ++j) {
            const float u = float(o.free_space_w_mm) * (float(i) / 4 - 0.5f), w = float(o.free_space_h_mm) * (float(j) / 3 - 0.5f);
            const V3 p = add(add(add(f.t, mul(f.x, u)), mul(f.y, w)), mul(f.z, -float(o.free_space_mm)));
            const int64_t c = cell_of(g, p);
            if (c < 0 || g.cells[c * 2] < 0) continue;
            const float* q = g.dense + int64_t(g.cells[c * 2]) * 6;
            const float depth = -dot(sub(p, load3(q)), load3(q + 3));
            if (depth > 0) v += robust_log((depth / s) * (depth / s), exp_floor) - zero;
        }
    return v;
}

// Pattern search over six degrees of freedom from x on objective f (rotations about the
// pose's axes from step_r, shifts from step_t, halved `rounds` times); fx: x's value, then the result's.
// With a pivot (the candidates protocol, where a candidate is a place, and a climb that left it
// would credit it with another place's fit): the turns are about the pivot and the only shift is
// along the gel's axis, so a pivot on the axis stays on it, at the contact.
template <class F>
Rigid climb_on(const F& f, Rigid x, double& fx, int rounds, double step_r, double step_t,
               const std::array<double, 3>* pivot = nullptr) {
    for (int round = 0; round < rounds; ++round, step_r /= 2, step_t /= 2)
        for (bool moved = true; moved;) {
            moved = false;
            for (int k = 0; k < 6; ++k)
                for (double sign : {1.0, -1.0}) {
                    if (pivot && (k == 3 || k == 4)) continue;
                    double d[6] = {0, 0, 0, 0, 0, 0};
                    d[k] = sign * (k < 3 ? step_r : step_t);
                    Rigid y = perturb(x, d, pivot);
                    double fy = f(y);
                    if (fy > fx + 1e-9) x = y, fx = fy, moved = true;
                }
        }
    return x;
}

// The geometry's climb: from 4 degrees and 0.8 mm, halved six times.
Rigid climb(const ops::pose::Grid& grid, const std::vector<ops::pose::Term>& terms, const FilterOptions& o, Rigid x, double& fx,
            const std::array<double, 3>* pivot) {
    return climb_on([&](const Rigid& y) { return pose_fit(grid, terms, o, y); }, x, fx, 6, 4.0 * M_PI / 180, 0.8, pivot);
}

// How far odometry noise may have moved an earlier touch from where the motions carry it:
// steps motions back, at lever arm |rel.t| (term_row's widths without the surface's own).
struct Slack {
    double sigma_t = 0, sigma_r = 0;
    // The Gaussian log-prior of offsets e = (spin, shift x, shift y); a zero width holds its offsets at 0.
    double log_prior(const std::array<double, 3>& e) const {
        double v = 0;
        if (sigma_r > 0) v -= 0.5 * e[0] * e[0] / (sigma_r * sigma_r);
        if (sigma_t > 0) v -= 0.5 * (e[1] * e[1] + e[2] * e[2]) / (sigma_t * sigma_t);
        return v;
    }
};
Slack slack_of(const Rigid& rel, int steps, const FilterOptions& o) {
    const double lever2 = rel.t[0] * rel.t[0] + rel.t[1] * rel.t[1] + rel.t[2] * rel.t[2];
    const double od = o.odometry_deg * M_PI / 180;
    return {std::sqrt(steps * (o.odometry_mm * o.odometry_mm + od * od * lever2)), std::sqrt(double(steps)) * od};
}

// A pose term taken where it is best near pose x: offsets d = (spin about the gel's axis,
// shift along its x, shift along its y) within the slack, each paying the Gaussian's log.
// The render-and-compare score ignores the press's depth and tilt, so those stay. d: where the
// search starts (the last alignment), then what it found; returns the term plus the prior.
double aligned_term(const PoseTerm& term, const Rigid& x, const Slack& sl, int rounds, std::array<double, 3>& d) {
    auto at = [&](const std::array<double, 3>& e) {
        const double v[6] = {0, 0, e[0], e[1], e[2], 0};
        return term(perturb(x, v)) + sl.log_prior(e);
    };
    double fd = at(d);
    double step[3] = {sl.sigma_r, sl.sigma_t, sl.sigma_t};
    for (int round = 0; round < rounds; ++round) {
        for (bool moved = true; moved;) {
            moved = false;
            for (int k = 0; k < 3; ++k)
                for (double sign : {1.0, -1.0}) {
                    if (!(step[k] > 0)) continue;
                    std::array<double, 3> e = d;
                    e[size_t(k)] += sign * step[k];
                    const double fe = at(e);
                    if (fe > fd + 1e-9) d = e, fd = fe, moved = true;
                }
        }
        for (double& s : step) s /= 2;
    }
    return fd;
}

// The refinement: with o.refine_widen > 0 it first climbs at the grid's widths times that (a
// smoother landscape, which a pose several degrees off can climb: at long lever arms
// the tight one's basin is a degree or two wide), then at the tight widths. With
// o.refine_reach_mm > 0 it also climbs from the nearest touches outward (below) and keeps
// the better fit. The term sets are made once per window (Refiner), not once per mode.
struct Refiner {
    const ops::pose::Grid& grid;
    const FilterOptions& o;
    std::vector<ops::pose::Term> tight, wide;
    // The reach's stages: the tight terms within reach, 2 reach, 4 reach, ... of the
    // current touch (lever arm = the motion's translation), each a proper subset.
    std::vector<std::vector<ops::pose::Term>> stages;
    bool slide = true;  // false: the candidates protocol (climb_on)
    const LazyNearestFacing* nearest = nullptr;  // the registration's (null or empty: off)
    Refiner(const ops::pose::Grid& g, const std::vector<Rigid>& to_window, const FilterOptions& opt, double spacing, int n_spin,
            bool slide_, const LazyNearestFacing* nf = nullptr)
        : grid(g), o(opt), tight(fit_terms(to_window, opt)), slide(slide_), nearest(nf) {
        const double f = opt.refine_widen * opt.grid_allowance;
        if (opt.refine_widen > 0) wide = fit_terms(to_window, opt, f * spacing, f * 2 * M_PI / n_spin);
        if (opt.refine_reach_mm > 0)
            for (double reach = opt.refine_reach_mm;; reach *= 2) {
                std::vector<ops::pose::Term> near;
                for (const ops::pose::Term& t : tight)
                    if (std::sqrt(t.trel[0] * t.trel[0] + t.trel[1] * t.trel[1] + t.trel[2] * t.trel[2]) <= reach) near.push_back(t);
                if (near.size() == tight.size()) break;
                if (!near.empty() && (stages.empty() || near.size() > stages.back().size())) stages.push_back(std::move(near));
            }
    }
    double fit(const Rigid& x) const { return pose_fit(grid, tight, o, x); }
    // Free space behind every touch of the window, scored once a climb has ended: the climbs
    // find where the contacts fit, this tells apart places that fit alike.
    double free_space(const Rigid& x) const {
        if (!(o.free_space_mm > 0)) return 0;
        const ops::pose::Frame f = frame_of(x);
        double v = free_space_log(grid, f, o);
        for (const ops::pose::Term& t : tight) v += free_space_log(grid, ops::pose::moved(f, t), o);
        return v;
    }
    bool can_register() const { return slide && nearest && !nearest->no_points() && o.register_rounds > 0 && o.refine > 0; }
    // A refined pose x (fit fx, free space included) registered onto the surface
    // (register_window) and climbed again; the better of the two kept.
    Rigid reregister(const Rigid& x, double& fx) const {
        return can_register() ? climbed_if_better(register_window(nearest->get(), tight, o, x), x, fx, nullptr) : x;
    }
    // y climbed at the tight widths where it then fits (free space included) better than x
    // does (fx, updated), else x.
    Rigid climbed_if_better(Rigid y, const Rigid& x, double& fx, const std::array<double, 3>* pv) const {
        double fy = fit(y);
        y = climb(grid, tight, o, y, fy, pv);
        fy += free_space(y);
        if (fy > fx) {
            fx = fy;
            return y;
        }
        return x;
    }
    // x refined (when o.refine > 0); fx: its tight fit plus its free space. Without slide the
    // climbs turn about x's contact (its axis at the press) and keep it there.
    Rigid refine(Rigid x, double& fx) const {
        const std::array<double, 3> contact{x.t[0] - o.press_mm * x.R[2], x.t[1] - o.press_mm * x.R[5], x.t[2] - o.press_mm * x.R[8]};
        const std::array<double, 3>* pv = slide ? nullptr : &contact;
        if (o.refine > 0 && o.refine_widen > 0) {
            double fw = pose_fit(grid, wide, o, x);
            x = climb(grid, wide, o, x, fw, pv);
        }
        fx = fit(x);
        if (o.refine == 0) {
            fx += free_space(x);
            return x;
        }
        Rigid direct = climb(grid, tight, o, x, fx, pv);
        fx += free_space(direct);
        if (stages.empty()) return direct;
        // From the nearest touches outward: a pose a spin step off puts the far touches of a
        // long lever arm outside the tight basin, where the direct climb finds no slope; the
        // near ones fix the pose's place and spin first. Near touches alone leave directions
        // flat, along which that climb may drift, so the direct climb's pose stays when it
        // fits better (ties too).
        for (const auto& near : stages) {
            double fn = pose_fit(grid, near, o, x);
            x = climb(grid, near, o, x, fn, pv);
        }
        return climbed_if_better(x, direct, fx, pv);
    }
};

// Each earlier touch of a window in the current touch's frame, oldest first.
std::vector<Rigid> window_in_current(const std::vector<Rigid>& motions) {
    std::vector<Rigid> out(motions.size());
    Rigid chain;  // from the newest back
    for (size_t k = motions.size(); k-- > 0;) {
        chain = compose(motions[k], chain);
        out[k] = inverse(chain);
    }
    return out;
}

}  // namespace

double slack_radius(const Surface& s) { return std::max(2 * s.spacing_mm, 4.0); }

std::array<float, 2> slack_widths(const Rigid& rel, int steps, const FilterOptions& o) {
    const Slack sl = slack_of(rel, steps, o);
    return {sl.sigma_t > 0 ? float(0.5 / (sl.sigma_t * sl.sigma_t)) : 0.0f, sl.sigma_r > 0 ? float(0.5 / (sl.sigma_r * sl.sigma_r)) : 0.0f};
}

double Tracker::max_hop_mm() const {
    return surface_->diameter + 2 * (std::abs(opt_.press_mm) + kHopSlackMm) + 6 * std::sqrt(3.0) * opt_.odometry_mm;
}

void Tracker::check_motion(const Rigid& m, size_t touch) const {
    const std::string what = "touch " + std::to_string(touch) + "'s motion";
    check_rigid(m, what);
    const double hop = std::sqrt(m.t[0] * m.t[0] + m.t[1] * m.t[1] + m.t[2] * m.t[2]), most = max_hop_mm();
    if (hop > most) {
        char buf[320];
        std::snprintf(buf, sizeof buf,
                      ": the sensor moves %.4g mm, farther than two touches on this object can be apart (%.4g mm: its bounding "
                      "box's diagonal, %.4g, the presses and the odometry noise); is the object file in the robot's units? "
                      "(object_units, --object-units)",
                      hop, most, surface_->diameter);
        throw Error(what + buf);
    }
}

void Tracker::check_term(const std::vector<float>& term, size_t touch) const {
    const int64_t H = surface_->n_hypotheses();
    if (!term.empty() && int64_t(term.size()) != H)
        throw Error("touch " + std::to_string(touch) + ": its term has " + std::to_string(term.size()) + " values for " +
                    std::to_string(H) + " hypotheses");
    for (float v : term)
        if (std::isnan(v) || v == INFINITY) throw Error("touch " + std::to_string(touch) + ": its term holds NaN or +inf");
}

Tracker::Step Tracker::run_step(const std::vector<Rigid>& motions, const std::vector<const std::vector<float>*>& terms,
                                const Rigid* prior_motion, const std::vector<float>* prior) {
    const int64_t m = int64_t(motions.size()) + 1, H = surface_->n_hypotheses();
    bool any_term = false;
    for (const auto* t : terms) any_term = any_term || (t && !t->empty());
    const int64_t n_term_fields = any_term ? m : 0, F = n_term_fields + (prior ? 1 : 0), K = m - 1 + (prior ? 1 : 0);
    const std::pair<int64_t, int64_t> key{K, F};
    if (impl_->ctx && !impl_->exec.count(key))
        impl_->exec[key] = std::make_unique<GpuExecutor>(*impl_->ctx, step_graph(*surface_, opt_, K, F, any_term ? m - 1 : -1),
                                                         impl_->weights, impl_->resident, impl_->profile);
    if (!impl_->ctx && !impl_->graphs.count(key)) impl_->graphs.emplace(key, step_graph(*surface_, opt_, K, F, any_term ? m - 1 : -1));
    Step st;
    st.to_window = window_in_current(motions);
    HostTensor tr({K, 16}), fields({F, H});
    for (int64_t k = 0; k < m - 1; ++k) {
        const bool has = any_term && terms[size_t(k)] && !terms[size_t(k)]->empty();
        term_row(&tr.data[size_t(16 * k)], st.to_window[size_t(k)], int(m - 1 - k), opt_, has ? int(k) : -1, opt_.term_weight,
                 opt_.grid_allowance * surface_->spacing_mm, opt_.grid_allowance * 2 * M_PI / surface_->n_spin());
    }
    // field_slack's widths: a_t = 1 / (2 sigma_t^2), a_r = 1 / (2 sigma_r^2) of each earlier field's
    // odometry slack; the current touch's own field has none (0).
    HostTensor widths({F, 2});
    auto set_widths = [&](int64_t f, const Rigid& rel, int steps) {
        const std::array<float, 2> a = slack_widths(rel, steps, opt_);
        widths.data[size_t(2 * f)] = a[0], widths.data[size_t(2 * f + 1)] = a[1];
    };
    for (int64_t f = 0; f + 1 < n_term_fields; ++f) set_widths(f, st.to_window[size_t(f)], int(m - 1 - f));
    if (prior) {
        // The touch before the window: its belief read at the pose the motions lead back to (no geometry: its
        // belief holds it). The read is at the nearest hypothesis; the window's own geometry is exact.
        const Rigid back = compose(m > 1 ? st.to_window[0] : Rigid{}, inverse(*prior_motion));
        set_widths(F - 1, back, int(m));
        term_row(&tr.data[size_t(16 * (K - 1))], back, int(m), opt_, int(F - 1), 1.0);
        tr.data[size_t(16 * (K - 1) + 12)] = 0;
        std::copy(prior->begin(), prior->end(), fields.data.begin() + (F - 1) * H);
    }
    for (int64_t f = 0; f < n_term_fields; ++f)
        if (terms[size_t(f)] && !terms[size_t(f)]->empty())
            for (int64_t h = 0; h < H; ++h)
                fields.data[size_t(f * H + h)] = (f == m - 1 ? float(opt_.term_weight) : 1.0f) * (*terms[size_t(f)])[size_t(h)];
    TensorMap in{{"terms", std::move(tr)}, {"fields", std::move(fields)}};
    if (slack_on(opt_) && F > 0) in.emplace("widths", std::move(widths));
    TensorMap out = impl_->ctx ? impl_->exec.at(key)->run(in) : run_cpu(impl_->graphs.at(key), impl_->weights, in);
    if (impl_->capture) {
        impl_->last_case = StepCase{Graph{}, std::move(in)};
        impl_->graph_of = std::array<int64_t, 3>{K, F, any_term ? m - 1 : -1};
    }
    impl_->last_exec = key;
    st.log = std::move(out.at("log").data);
    st.prob = std::move(out.at("prob").data);
    st.marginal = std::move(out.at("marginal").data);
    st.cost = std::move(out.at("cost").data);
    return st;
}

void Tracker::add_touch(const std::optional<Rigid>& motion, const std::vector<float>& term, PoseTerm pose_term) {
    const size_t n = size_t(touches_) + 1;
    if (touches_ == 0 && motion) throw Error("touch 1: the first touch has no previous one to move from");
    if (touches_ > 0 && !motion) throw Error("touch " + std::to_string(n) + ": needs the motion from the previous touch");
    if (motion) check_motion(*motion, n);
    check_term(term, n);
    // The window: the last online_window touches, this one included; the belief of
    // the touch before it (when there is one) enters as a prior.
    if (motion) motions_.push_back(*motion);
    terms_.push_back(term);
    pose_terms_.push_back(std::move(pose_term));
    const size_t W = size_t(std::max(1, opt_.online_window));
    std::optional<Rigid> prior_motion;
    if (terms_.size() > W) {
        prior_motion = motions_.front();
        motions_.erase(motions_.begin());
        terms_.erase(terms_.begin());
        pose_terms_.erase(pose_terms_.begin());
    }
    std::vector<const std::vector<float>*> tp;
    for (const auto& t : terms_) tp.push_back(&t);
    Step st = run_step(motions_, tp, prior_motion ? &*prior_motion : nullptr, prior_motion ? &prior_log_ : nullptr);
    // The belief a later touch reads as its prior is the one of the touch that leaves its window next.
    beliefs_.push_back(st.log);
    if (beliefs_.size() > W) beliefs_.erase(beliefs_.begin());
    prior_log_ = beliefs_.front();
    last_ = std::move(st);
    ++touches_;
}

void Tracker::reset() {
    touches_ = 0;
    last_ = Step{};
    motions_.clear();
    terms_.clear();
    pose_terms_.clear();
    beliefs_.clear();
    prior_log_.clear();
}

uint64_t Tracker::device_bytes() const {
    uint64_t arenas = 0;  // the tables go up with the first step graph; count them from the start
    for (const auto& [key, ex] : impl_->exec) arenas += ex->memory_plan().arena_bytes + ex->memory_plan().scratch_bytes;
    return std::max(surface_->device_bytes(), impl_->resident ? impl_->resident->bytes() : 0) + arenas;
}

void Tracker::profile_steps(bool on) {
    if (on == impl_->profile) return;
    impl_->profile = on;
    impl_->exec.clear();  // made again, with or without timestamps, at their next step
    impl_->last_exec.reset();
}

std::vector<std::pair<std::string, double>> Tracker::step_node_times() const {
    std::vector<std::pair<std::string, double>> t;
    if (impl_->ctx && impl_->profile && impl_->last_exec)
        for (const auto& n : impl_->exec.at(*impl_->last_exec)->node_times()) t.emplace_back(n.label, n.ms);
    return t;
}

void Tracker::capture_steps(bool on) {
    impl_->capture = on;
    if (!on) impl_->last_case.reset(), impl_->graph_of.reset();
}

const Tracker::StepCase* Tracker::last_step_case() const {
    if (!impl_->last_case) return nullptr;
    if (const auto g = impl_->graph_of) {
        impl_->last_case->graph = step_graph(*surface_, opt_, (*g)[0], (*g)[1], (*g)[2]);
        impl_->graph_of.reset();
    }
    return &*impl_->last_case;
}

const WeightStore& Tracker::step_weights() const { return impl_->weights; }

uint64_t Tracker::host_bytes() const {
    return surface_->host_bytes() + impl_->weights.bytes() + (impl_->nearest ? impl_->nearest->bytes() : 0) +
           (impl_->pairs ? impl_->pairs->bytes() : 0);
}

Estimate Tracker::estimate() const {
    if (touches_ == 0) throw Error("the tracker has no touch yet");
    return finish(last_.log, last_.marginal, last_.cost, last_.to_window, pose_terms_);
}

Estimate Tracker::evaluate_window(const std::vector<Rigid>& motions, const std::vector<std::vector<float>>& terms,
                                  const std::vector<PoseTerm>& pose_terms) {
    const size_t W = motions.size() + 1;
    if (!terms.empty() && terms.size() != W)
        throw Error("window: " + std::to_string(terms.size()) + " touch terms for " + std::to_string(W) + " touches");
    if (!pose_terms.empty() && pose_terms.size() != W)
        throw Error("window: " + std::to_string(pose_terms.size()) + " pose terms for " + std::to_string(W) + " touches");
    for (size_t i = 0; i < motions.size(); ++i) check_motion(motions[i], i + 2);
    std::vector<const std::vector<float>*> tp(W, nullptr);
    for (size_t i = 0; i < terms.size(); ++i) check_term(terms[i], i + 1), tp[i] = &terms[i];
    Step st = run_step(motions, tp, nullptr, nullptr);
    return finish(st.log, st.marginal, st.cost, st.to_window, pose_terms);
}

double Tracker::window_fit(const std::vector<Rigid>& motions, const Rigid& pose) const {
    for (size_t i = 0; i < motions.size(); ++i) check_motion(motions[i], i + 2);
    check_rigid(pose, "the pose to fit");
    const ops::pose::Grid grid = surface_->grid();
    double f = 0;
    const Refiner r(grid, window_in_current(motions), opt_, surface_->spacing_mm, surface_->n_spin(), !surface_->from_candidates, impl_->nearest.get());
    const Rigid x = r.refine(pose, f);
    if (f < opt_.rescue_fit) r.reregister(x, f);
    return f;
}

Estimate Tracker::finish(const std::vector<float>& log, const std::vector<float>& marginal, const std::vector<float>& cost,
                         const std::vector<Rigid>& to_window, const std::vector<PoseTerm>& pose_terms) const {
    const Surface& s = *surface_;
    const int64_t S = s.n_samples(), NS = s.n_spin();
    const ops::pose::Grid grid = s.grid();
    auto point = [&](int64_t i) { return std::array<double, 3>{s.samples[size_t(9 * i)], s.samples[size_t(9 * i + 1)], s.samples[size_t(9 * i + 2)]}; };
    auto dist = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
        return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    };
    Estimate e;
    const int64_t stride = answer_stride(s);

    // Modes: greedy non-maximum suppression over the samples' belief; owner[j]: the
    // first mode within the radius of sample j (-1: none), used for every mode mass below.
    std::vector<int64_t> order(static_cast<size_t>(S));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int64_t a, int64_t b) { return marginal[size_t(a)] > marginal[size_t(b)]; });
    std::vector<int> owner(static_cast<size_t>(S), -1);
    std::vector<int64_t> mode_sample;
    size_t next = 0;  // where the greedy suppression goes on from
    auto more_modes = [&](int count) {
        for (; next < order.size() && int(mode_sample.size()) < count; ++next) {
            const int64_t i = order[next];
            if (owner[size_t(i)] >= 0) continue;
            const int m = int(mode_sample.size());
            const std::array<double, 3> pi = point(i);
            const double r = opt_.mode_radius_mm;
            for (int64_t j = 0; j < S; ++j) {
                if (owner[size_t(j)] >= 0) continue;
                // A coordinate more than r apart rules j out without the square root: the
                // rounded distance is never below any one coordinate's difference.
                const std::array<double, 3> pj = point(j);
                if (std::abs(pj[0] - pi[0]) > r || std::abs(pj[1] - pi[1]) > r || std::abs(pj[2] - pi[2]) > r) continue;
                if (dist(pj, pi) <= r) owner[size_t(j)] = m;
            }
            mode_sample.push_back(i);
        }
    };
    more_modes(opt_.n_modes);

    // Refinement: the best spin at each of the best modes, then a pattern search
    // over six degrees of freedom on the window's geometry (the current touch's too).
    const Refiner refiner(grid, to_window, opt_, s.spacing_mm, int(NS), !s.from_candidates, impl_->nearest.get());
    // The refined modes share the grid mass they hold by their refined fit (the
    // window's geometry at the tight widths): the grid, whose widths must cover
    // its own spacing, cannot tell a true pose between its hypotheses from a
    // near miss. Samples outside the refined modes keep their grid mass.
    // shape[m]: the window's pose terms at refined mode m's poses (render-and-compare there),
    // added to its fit where the refined modes share the mass.
    std::vector<double> fit, shape;
    std::vector<Rigid> refined;
    std::vector<std::array<double, 3>> refined_contact;
    // The hypothesis of sample smp at its most likely spin (the first on ties).
    auto best_spin_pose = [&](int64_t smp) {
        int64_t hb = smp * NS;
        for (int64_t j = 1; j < NS; ++j)
            if (log[size_t(smp * NS + j)] > log[size_t(hb)]) hb = smp * NS + j;
        return rigid_of(ops::pose::hypothesis_frame(grid, hb, float(opt_.press_mm)));
    };
    const bool any_pose_term = std::any_of(pose_terms.begin(), pose_terms.end(), [](const PoseTerm& t) { return bool(t); });
    auto refine_modes = [&](int upto) {
        const size_t from = fit.size(), n = size_t(std::max<int>(0, upto - int(from)));
        fit.resize(from + n);
        shape.resize(from + n);
        refined.resize(from + n);
        refined_contact.resize(from + n);
        // Each mode's climb is independent and pure, so the modes are spread over the host's
        // threads (the GPU waits for the estimate anyway); every climb writes its own slot,
        // so the result is the same with any number of threads.
        auto climb_mode = [&](size_t m) {
            const int64_t smp = mode_sample[m];
            refined[m] = refiner.refine(best_spin_pose(smp), fit[m]);
            // A candidate's refined pose turns about the candidate and keeps it (climb_on's pivot).
            refined_contact[m] = s.from_candidates ? point(smp) : axis_contact(s, grid, refined[m], opt_.press_mm);
        };
        parallel_for(n, opt_.threads, [&](size_t i) { climb_mode(from + i); });
    };
    refine_modes(std::max(1, std::min<int>(opt_.refine, int(mode_sample.size()))));
    const int n_first = int(fit.size());
    if (opt_.refine > 0 && *std::max_element(fit.begin(), fit.end()) < opt_.rescue_fit) {
        more_modes(int(mode_sample.size()) + opt_.rescue_modes);
        refine_modes(int(mode_sample.size()));
    }
    int n_refine = int(fit.size());
    // Registers (Refiner::reregister) the refined modes below upto not registered yet; each
    // keeps the better fit, so a mode is registered at most once.
    std::vector<char> registered(fit.size(), 0);
    auto register_modes = [&](int upto) {
        std::vector<size_t> todo;
        for (size_t m = 0; m < size_t(upto); ++m)
            if (!registered[m]) todo.push_back(m), registered[m] = 1;
        parallel_for(todo.size(), opt_.threads, [&](size_t i) {
            const size_t m = todo[i];
            refined[m] = refiner.reregister(refined[m], fit[m]);
            refined_contact[m] = axis_contact(s, grid, refined[m], opt_.press_mm);
        });
    };
    // Where nothing refined fits the window (the rescue's threshold), the first modes are also
    // registered onto the surface: the rescued ones gained nothing on the train windows and
    // cost four times the time.
    if (refiner.can_register() && *std::max_element(fit.begin(), fit.end()) < opt_.rescue_fit) register_modes(n_first);
    // Deep search: where even the registered modes leave touches off the surface, the truth's
    // mode may rank anywhere on the grid (at the truth's nearest hypothesis the far touches
    // miss by more than the grid's widths), so every mode not yet refined is registered from
    // its best spin and the best by fit are climbed and refined beside the others.
    const int n_before_deep = n_refine;
    if (refiner.can_register() && opt_.deep_modes > 0 && *std::max_element(fit.begin(), fit.end()) < opt_.deep_fit) {
        // The deep modes are registered, so every refined mode is too (with the fitted
        // thresholds the first ones were above, so these are the rescued): a mode climbed alone
        // would lose to a registered one that fits no better than it could.
        if (opt_.deep_registers_refined) register_modes(n_refine);
        more_modes(int(S));
        const size_t first = size_t(n_refine), n_seeds = mode_sample.size() - first;
        std::vector<double> seed_fit(n_seeds);
        std::vector<Rigid> seed_pose(n_seeds);
        parallel_for(n_seeds, opt_.threads, [&](size_t i) {
            seed_pose[i] = register_window(refiner.nearest->get(), refiner.tight, opt_, best_spin_pose(mode_sample[first + i]), opt_.register_cap);
            seed_fit[i] = refiner.fit(seed_pose[i]);
        });
        // The pair search's poses, each the seed of its nearest unsearched mode where it fits
        // better than that mode's registered seed (as it is or registered, the better).
        if (impl_->pairs && opt_.pair_modes > 0 && n_seeds > 0) {
            std::vector<ops::pose::Term> touches = refiner.tight;
            touches.push_back(own_term(opt_));
            PairSearchOptions po;
            po.top = opt_.pair_modes;
            po.threads = opt_.threads;
            const std::vector<Rigid> cands = pair_candidates(*impl_->pairs, grid, touches, opt_.press_mm, opt_.log_floor,
                                                             [&](const Rigid& x) { return refiner.fit(x); }, po);
            std::vector<double> cand_fit(cands.size());
            std::vector<Rigid> cand_pose(cands.size());
            parallel_for(cands.size(), opt_.threads, [&](size_t i) {
                const Rigid y = register_window(refiner.nearest->get(), refiner.tight, opt_, cands[i], opt_.register_cap);
                const double fx = refiner.fit(cands[i]), fy = refiner.fit(y);
                cand_pose[i] = fy > fx ? y : cands[i], cand_fit[i] = std::max(fx, fy);
            });
            for (size_t i = 0; i < cands.size(); ++i) {
                const std::array<double, 3> at = axis_contact(s, grid, cand_pose[i], opt_.press_mm);
                size_t near = 0;
                for (size_t k = 1; k < n_seeds; ++k)
                    if (dist(point(mode_sample[first + k]), at) < dist(point(mode_sample[first + near]), at)) near = k;
                if (cand_fit[i] > seed_fit[near]) seed_fit[near] = cand_fit[i], seed_pose[near] = cand_pose[i];
            }
        }
        std::vector<size_t> by(n_seeds);
        std::iota(by.begin(), by.end(), size_t(0));
        const size_t D = std::min(n_seeds, size_t(opt_.deep_modes));
        std::partial_sort(by.begin(), by.begin() + long(D), by.end(),
                          [&](size_t a, size_t b) { return seed_fit[a] > seed_fit[b] || (seed_fit[a] == seed_fit[b] && a < b); });
        // The chosen modes move to the front of the unrefined ones: mode indices swapped, with
        // the samples each owns.
        std::vector<int64_t> chosen(D);
        for (size_t k = 0; k < D; ++k) chosen[k] = mode_sample[first + by[k]];
        for (size_t k = 0; k < D; ++k) {
            const int a = int(first + k);
            const int b = int(std::find(mode_sample.begin() + long(first), mode_sample.end(), chosen[k]) - mode_sample.begin());
            std::swap(mode_sample[size_t(a)], mode_sample[size_t(b)]);
            for (int& ow : owner) ow = ow == a ? b : ow == b ? a : ow;
        }
        fit.resize(first + D), shape.resize(first + D), refined.resize(first + D), refined_contact.resize(first + D);
        parallel_for(D, opt_.threads, [&](size_t k) {
            const Rigid& y = seed_pose[by[k]];
            fit[first + k] = -INFINITY;
            refined[first + k] = refiner.climbed_if_better(y, y, fit[first + k], nullptr);
            refined_contact[first + k] = axis_contact(s, grid, refined[first + k], opt_.press_mm);
        });
        n_refine = int(first + D);
    }
    if (any_pose_term) {
        // With odometry noise each earlier touch's term is aligned within its slack (the
        // offsets found per mode and touch, align[m]); the climb holds them, then they are found
        // again at the pose it reached.
        std::vector<Slack> slack(to_window.size());
        bool any_slack = false;
        if (opt_.shape_slack_rounds > 0)
            for (size_t k = 0; k < to_window.size(); ++k) {
                slack[k] = slack_of(to_window[k], int(to_window.size() - k), opt_);
                any_slack = any_slack || slack[k].sigma_t > 0 || slack[k].sigma_r > 0;
            }
        using Offsets = std::vector<std::array<double, 3>>;
        std::vector<Offsets> align(static_cast<size_t>(n_refine), Offsets(pose_terms.size(), std::array<double, 3>{}));
        auto shape_at = [&](const Rigid& x, const Offsets& d) {
            double v = 0;
            for (size_t k = 0; k < pose_terms.size(); ++k) {
                if (!pose_terms[k]) continue;
                if (k >= to_window.size()) {
                    v += pose_terms[k](x);
                    continue;
                }
                const double e[6] = {0, 0, d[k][0], d[k][1], d[k][2], 0};
                v += pose_terms[k](perturb(compose(x, to_window[k]), e)) + slack[k].log_prior(d[k]);
            }
            return v;
        };
        auto align_at = [&](const Rigid& x, Offsets& d) {
            if (!any_slack) return shape_at(x, d);
            double v = 0;
            for (size_t k = 0; k < pose_terms.size(); ++k)
                if (pose_terms[k])
                    v += k < to_window.size() && (slack[k].sigma_t > 0 || slack[k].sigma_r > 0)
                             ? aligned_term(pose_terms[k], compose(x, to_window[k]), slack[k], opt_.shape_slack_rounds, d[k])
                             : pose_terms[k](k < to_window.size() ? compose(x, to_window[k]) : x);
            return v;
        };
        parallel_for(size_t(n_refine), opt_.threads, [&](size_t m) { shape[m] = align_at(refined[m], align[m]); });
        // Where the geometry leaves directions flat (touches on one face slide along it), the
        // climb stopped wherever the grid's pose lay; the gel's shapes tell along them. So the
        // best few modes by geometry + shapes climb on both (a render per touch per step: the
        // rest only score), each keeping what it finds where that, with free space, is better.
        std::vector<size_t> by_total(static_cast<size_t>(n_refine));
        std::iota(by_total.begin(), by_total.end(), size_t(0));
        std::stable_sort(by_total.begin(), by_total.end(), [&](size_t a, size_t b) { return fit[a] + shape[a] > fit[b] + shape[b]; });
        by_total.resize(std::min(by_total.size(), size_t(std::max(0, opt_.shape_climb_modes))));
        if (opt_.refine > 0 && opt_.shape_climb_rounds > 0)
            parallel_for(by_total.size(), opt_.threads, [&](size_t i) {
                const size_t m = by_total[i];
                const std::array<double, 3> sample_at = point(mode_sample[m]);  // its candidate, without slide
                double fb = refiner.fit(refined[m]) + shape[m];
                Offsets d = align[m];
                const Rigid y = climb_on([&](const Rigid& x) { return refiner.fit(x) + shape_at(x, d); }, refined[m], fb,
                                         opt_.shape_climb_rounds, 2.0 * M_PI / 180, 0.8, refiner.slide ? nullptr : &sample_at);
                const double fy = refiner.fit(y) + refiner.free_space(y), sy = align_at(y, d);
                if (fy + sy > fit[m] + shape[m]) {
                    refined[m] = y, fit[m] = fy, shape[m] = sy;
                    refined_contact[m] = s.from_candidates ? sample_at : axis_contact(s, grid, y, opt_.press_mm);
                }
            });
    }
    // The modes are in three runs: the first [0, n_first), the rescued [n_first, n_before_deep)
    // and the deep [n_before_deep, n_refine). A rescued mode is credited with its refined fit
    // only while its pose stays within the suppression radius of its own sample: else it would
    // lend another place's fit to its own. A deep mode was chosen by where it lands, and is
    // credited there.
    std::vector<char> ok(static_cast<size_t>(n_refine), 1);
    for (int m = n_first; m < n_before_deep; ++m)
        ok[size_t(m)] = dist(refined_contact[size_t(m)], point(mode_sample[size_t(m)])) <= opt_.mode_radius_mm;
    e.modes.assign(mode_sample.size(), Mode{});
    for (size_t m = 0; m < mode_sample.size(); ++m) e.modes[m].contact = point(mode_sample[m]);
    // owner is -1 for samples no mode claimed: test the bounds before reading ok.
    auto refined_mode = [&](int64_t i) {
        const int m = owner[size_t(i)];
        return m >= 0 && m < n_refine && ok[size_t(m)] ? m : -1;
    };
    std::vector<double> grid_mass(static_cast<size_t>(n_refine), 0.0);
    for (int64_t i = 0; i < S; ++i)
        if (refined_mode(i) >= 0) grid_mass[size_t(refined_mode(i))] += marginal[size_t(i)];
    std::vector<double> share(static_cast<size_t>(n_refine));
    for (int m = 0; m < n_refine; ++m) share[size_t(m)] = fit[size_t(m)] + shape[size_t(m)];
    double fmax = -INFINITY;
    for (int m = 0; m < n_refine; ++m)
        if (ok[size_t(m)]) fmax = std::max(fmax, share[size_t(m)]);
    double held = 0, z = 0;
    for (int m = 0; m < n_refine; ++m)
        if (ok[size_t(m)]) held += grid_mass[size_t(m)], z += std::exp(share[size_t(m)] - fmax);
    // Where the deep search found a mode that fits better than every mode the grid ranked
    // first, the samples no refined mode holds (ranked below those) lose mass as those modes
    // did: else a deep mode with little or no grid mass gets a share of the refined modes'
    // mass only, and the unrefined rest outweighs the place the geometry found.
    double rest = 1;
    if (n_refine > n_before_deep) {
        double fpre = -INFINITY;
        for (int m = 0; m < n_before_deep; ++m)
            if (ok[size_t(m)]) fpre = std::max(fpre, share[size_t(m)]);
        rest = std::exp(std::min(0.0, fpre - fmax));
    }
    std::vector<double> w(static_cast<size_t>(S));
    double total = 0;
    for (int64_t i = 0; i < S; ++i) {
        const int m = refined_mode(i);
        w[size_t(i)] = m < 0 ? rest * double(marginal[size_t(i)]) : grid_mass[size_t(m)] <= 0
                           ? double(marginal[size_t(i)])
                           : double(marginal[size_t(i)]) / grid_mass[size_t(m)] * held * std::exp(share[size_t(m)] - fmax) / z;
        total += w[size_t(i)];
    }
    // A deep mode may hold no grid mass at all (its samples' beliefs underflowed): its share
    // then sits at its own sample, whose place is its refined contact.
    for (int m = n_before_deep; m < n_refine; ++m)
        if (grid_mass[size_t(m)] <= 0) {
            const double v = held * std::exp(share[size_t(m)] - fmax) / z;
            w[size_t(mode_sample[size_t(m)])] += v, total += v;
        }
    for (double& v : w) v /= total;
    // Mode masses under the re-weighted belief; the pose is the heaviest refined mode's.
    for (int64_t i = 0; i < S; ++i)
        if (owner[size_t(i)] >= 0) e.modes[size_t(owner[size_t(i)])].probability += w[size_t(i)];
    int best_mode = 0;
    for (int m = 1; m < n_refine; ++m)
        if (ok[size_t(m)] && e.modes[size_t(m)].probability > e.modes[size_t(best_mode)].probability) best_mode = m;
    e.pose = refined[size_t(best_mode)];
    e.fit = fit[size_t(best_mode)];
    e.pose_terms = shape[size_t(best_mode)];
    // The Bayes contact under the re-weighted belief, each refined mode's mass at
    // its refined contact (its peak; the grid spreads it over the spacing), among
    // those contacts and the samples the GPU's risk ranked best.
    std::vector<std::array<double, 3>> at(static_cast<size_t>(S));
    for (int64_t i = 0; i < S; ++i) at[size_t(i)] = refined_mode(i) >= 0 ? refined_contact[size_t(refined_mode(i))] : point(i);
    std::vector<std::array<double, 3>> cand(refined_contact.begin(), refined_contact.end());
    std::vector<int64_t> by_cost(cost.size());
    std::iota(by_cost.begin(), by_cost.end(), 0);
    const size_t n_cost = std::min<size_t>(64, by_cost.size());
    std::partial_sort(by_cost.begin(), by_cost.begin() + long(n_cost), by_cost.end(),
                      [&](int64_t a, int64_t b) { return cost[size_t(a)] < cost[size_t(b)] || (cost[size_t(a)] == cost[size_t(b)] && a < b); });
    for (size_t i = 0; i < n_cost; ++i) cand.push_back(point(stride * by_cost[i]));
    for (size_t i = 0; i < std::min<size_t>(64, order.size()); ++i) cand.push_back(point(order[i]));  // the best-held samples
    // Only the samples with weight: a zero weight adds +0 to a sum of non-negative terms,
    // which leaves it as it is (past a few touches most of the belief underflows to 0).
    std::vector<int64_t> held_at;
    for (int64_t i = 0; i < S; ++i)
        if (w[size_t(i)] != 0) held_at.push_back(i);
    // Four candidates go over the samples together (one read of a sample for four sums, each
    // in the order it would have alone, so the same bits). A block stops once all four
    // partial risks have reached the best before it: the terms left are non-negative and a
    // rounded sum never drops, so none of them could have won.
    constexpr size_t B = 4;
    double best_risk = INFINITY;
    for (size_t c0 = 0; c0 < cand.size(); c0 += B) {
        const size_t nb = std::min(B, cand.size() - c0);
        std::array<double, 3> cb[B];
        for (size_t b = 0; b < B; ++b) cb[b] = cand[c0 + std::min(b, nb - 1)];  // a short block repeats its last
        double r[B] = {0, 0, 0, 0};
        for (size_t q = 0; q < held_at.size(); ++q) {
            const int64_t i = held_at[q];
            const double wi = w[size_t(i)];
            const std::array<double, 3>& a = at[size_t(i)];
            for (size_t b = 0; b < B; ++b) r[b] += wi * dist(a, cb[b]);
            if ((q & 63) == 63 && std::min(std::min(r[0], r[1]), std::min(r[2], r[3])) >= best_risk) break;
        }
        for (size_t b = 0; b < nb; ++b)
            if (r[b] < best_risk) best_risk = r[b], e.contact = cb[b];
    }
    e.mass_within_5mm = 0;
    for (int64_t i = 0; i < S; ++i)
        if (dist(at[size_t(i)], e.contact) <= 5.0) e.mass_within_5mm += w[size_t(i)];
    for (int m = 0; m < n_refine; ++m)
        if (ok[size_t(m)]) e.modes[size_t(m)].contact = refined_contact[size_t(m)];
    std::stable_sort(e.modes.begin(), e.modes.end(), [](const Mode& a, const Mode& b) { return a.probability > b.probability; });
    if (e.modes.size() > size_t(opt_.n_modes)) e.modes.resize(size_t(opt_.n_modes));
    e.sample_belief.assign(w.begin(), w.end());
    e.pose_contact = axis_contact(s, grid, e.pose, opt_.press_mm);
    for (const Rigid& r : to_window) e.window_poses.push_back(compose(e.pose, r));
    e.window_poses.push_back(e.pose);
    return e;
}

std::vector<float> Tracker::heatmap(const Estimate& e, const HostTensor& cloud) const {
    if (cloud.shape.size() != 2 || cloud.shape[1] < 3) throw Error("heat-map: the cloud must be [N, >= 3]");
    const int64_t N = cloud.shape[0], C = cloud.shape[1];
    std::vector<float> h(static_cast<size_t>(N), 0.0f);
    const ops::pose::Grid grid = surface_->grid();
    for (int64_t i = 0; i < N; ++i) {
        const float* q = &cloud.data[size_t(i * C)];
        const int64_t cell = surface_->cell_of(q);
        const int32_t near = C >= 6 ? ops::pose::pressed_point(grid, cell, P{-q[3], -q[4], -q[5]})
                             : cell < 0 ? -1 : surface_->cells[size_t(2 * cell)];
        const int32_t smp = near < 0 ? -1 : surface_->dense_sample[size_t(near)];
        if (smp >= 0) h[size_t(i)] = e.sample_belief[size_t(smp)];
    }
    if (h.empty()) return h;
    const auto [lo, hi] = std::minmax_element(h.begin(), h.end());
    const float a = *lo, b = *hi;
    for (float& v : h) v = b > a ? (v - a) / (b - a) : 0.0f;
    return h;
}

}  // namespace vtloc::track
