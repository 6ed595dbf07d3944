#pragma once
// The multi-touch filter (SPEC 6; docs/multitouch.md): a belief over sensor
// poses on the object's surface (hypotheses = surface samples x spins), moved on
// by the robot's relative motions and scored by the geometry of the touches
// (each pose must sit on the surface, its axis along the inward normal) and by
// optional touch terms (log fields over the hypotheses, e.g. the network's
// heat-map). Two forms: online (add_touch: the previous belief read at the
// pose the motion leads back to; a touch costs the same however many came
// before) and windowed (evaluate_window: the current touch and the W - 1 before
// it, each scored directly). Everything runs on the GPU; the ops' CPU
// references are the oracle (tests/test_tracker.cpp).
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "engine/graph.h"
#include "engine/rigid.h"
#include "engine/tensor.h"
#include "engine/track/surface.h"

namespace vtloc {
class WeightStore;
namespace rt {
class Context;
}
namespace track {

using vtloc::Rigid;
using vtloc::check_rigid;
using vtloc::compose;
using vtloc::inverse;

struct FilterOptions {
    double press_mm = 0.8;       // the press assumed for every touch (data: 0.3-1.5)
    double sigma_d_mm = 1.0;     // distance to the surface, at zero lever arm (fitted: weights_tools/fit_filter.py)
    double sigma_a_deg = 6;      // axis against the inward normal (fitted likewise)
    double odometry_mm = 0;      // motion noise per step, std, translation
    double odometry_deg = 0;     // and rotation (grows with the lever arm)
    double log_floor = -9;       // robust floor of one touch's geometry term (log)
    double grid_allowance = 0.25; // the grid's widths grow by this share of the spacing and spin step (fitted)
    double term_weight = 1;      // temperature of the touch terms
    double mode_radius_mm = 5;   // non-maximum suppression of the modes
    int n_modes = 8;
    int refine = 8;              // the best modes refined over six degrees of freedom
    double refine_widen = 0;     // > 0: refine at the grid's widths times this first, then at the tight ones
    // > 0: each mode is also refined from the nearest touches outward, the window's touches
    // within this lever arm first, then twice it, ... until all are in; the better of that
    // and the direct climb is kept (20 fitted on train windows: docs/multitouch.md, "Climbing
    // from the nearest touches"; 0: the direct climb alone).
    double refine_reach_mm = 20;
    // When the best refined fit is below rescue_fit (log; -inf: never; 0: always, a fit
    // being at most 0), the next rescue_modes modes are refined too: the truth's basin may
    // be one the grid ranked lower. A rescued mode whose refined pose leaves the suppression
    // radius of its own sample keeps its grid mass unrefined. Fitted on train windows
    // (docs/multitouch.md, "Refining more modes").
    double rescue_fit = -1;
    int rescue_modes = 24;
    // > 0: the refinement's fit also asks for free space behind the gel. The sensor sits where
    // its gel first touches the object over its window grown by a margin (free_space_w_mm x
    // free_space_h_mm), so points of that pad this far behind the gel plane lie outside the
    // object; one inside costs what a touch that far off the surface would (the robust
    // Gaussian at sigma_d). Tells a bolt's head from its flipped image (the shank would pass
    // through the sensor), which the touches' own contacts cannot. 1.5 fitted on train windows
    // (docs/multitouch.md, "Free space"); 0: off.
    double free_space_mm = 1.5;
    double free_space_w_mm = 24, free_space_h_mm = 19;  // the dataset sensor's 19.9 x 14.9 mm window, + 2 mm a side
    // > 0: where the best refined fit is below rescue_fit, the first `refine` modes are also
    // registered onto the surface (point-to-plane Gauss-Newton over the window's contacts, each
    // matched to the nearest dense point facing its gel at any distance) in this many rounds,
    // the widths annealed from register_scale times the tight ones down to them, then climbed;
    // the better fit kept. 12 and 8 fitted on train windows (docs/multitouch.md, "Registration").
    int register_rounds = 12;
    double register_scale = 8;
    // Where the best refined fit is still below deep_fit (log; -inf: never) after the
    // registration, the search has lost the touch: every suppression mode not yet refined is
    // registered from its best spin (each match searched within register_cap times its touch's
    // width at the round's scale; 0: at any distance), and the deep_modes best by fit are
    // climbed and refined beside the others (credited wherever they land). At the truth's
    // nearest hypothesis the far touches can miss by more than the grid's widths, so its mode
    // may rank anywhere on the grid. -5, 8 and 7 fitted on train windows
    // (docs/multitouch.md, "Deep search"); 0.02-0.4 s where it runs.
    double deep_fit = -5;
    int deep_modes = 8;
    double register_cap = 7;
    // Where the deep search runs, every refined mode not registered yet (with the fitted
    // thresholds: the rescued ones) is registered first, as the first modes were: the deep
    // ones are, and a mode only climbed can lose to one that fits no better than it would
    // registered. On train windows: 48 seen objects' score 14.638 -> 14.588
    // (docs/multitouch.md, "Deep search"); false: only the first modes, as before 2026-12-06.
    bool deep_registers_refined = true;
    // Where the deep search runs on a window spanning 60 mm or more, the pair search
    // (engine/track/pair_search.h) offers this many more seeds: poses that put the window's two
    // farthest contacts on surface points as far apart, with normals at the same angles, rolled
    // to a third touch. Each replaces the seed of its nearest unsearched mode where it fits
    // better (docs/multitouch.md, "Pair search": 48 seen objects' train score 14.588 -> 14.356);
    // 0: off.
    int pair_modes = 8;
    // Rounds of the climb on geometry + the touches' pose terms after the geometry's own
    // (steps from 2 degrees and 0.8 mm, halved each round); 0: the pose terms only score.
    int shape_climb_rounds = 3;
    int shape_climb_modes = 4;   // the refined modes best by geometry + pose terms that climb so
    // With odometry noise, each earlier touch's pose is the current one carried back by noisy
    // motions, so its pose term is taken where it is best within the noise's widths: a shift
    // along the gel and a spin about its axis, found by a pattern search of this many rounds
    // from one standard deviation, each offset paying its Gaussian log-prior. 0: carried rigidly.
    int shape_slack_rounds = 2;
    // With odometry noise, the grid reads each earlier touch's field (its render-and-compare
    // or network term; online, the prior belief) where it is best near the hypothesis the
    // motions lead to: over the neighbouring samples (kSlackNeighbours nearest within
    // slack_radius) and spins, each offset paying its Gaussian log-prior at the noise's
    // widths (the field_slack op). false: at the nearest hypothesis alone. Fitted on train windows
    // (docs/render_compare.md, "The grid's terms widened"): no change windowed, online worse, so off.
    bool field_slack = false;
    int online_window = 8;       // add_touch scores the last W touches exactly, older ones through a prior
    // Host threads an estimate climbs its modes on: 0, up to 4 (fewer where the host has
    // fewer); n, at most n (a robot process with its own thread budget). The outputs do not
    // depend on it: each mode's climb writes its own slot.
    int threads = 0;
};

// field_slack's neighbourhood (FilterOptions::field_slack): the kSlackNeighbours nearest samples within
// slack_radius, two sample spacings and at least 4 mm (the candidates protocol has no spacing; 0.5 mm and
// 0.5 degrees a motion reach ~1.5 mm by T = 8).
constexpr int kSlackNeighbours = 12;
double slack_radius(const Surface& s);
// field_slack's widths (a_t, a_r) = 1 / (2 sigma^2) for a field read `steps` noisy motions back over the
// relative pose rel: sigma_t^2 = steps (odometry_mm^2 + odometry_rad^2 |rel.t|^2), sigma_r^2 = steps
// odometry_rad^2; 0 where a width is 0 (that slack off).
std::array<float, 2> slack_widths(const Rigid& rel, int steps, const FilterOptions& o);

// A touch's own evidence (log) at an exact pose of that touch, asked of every refined mode
// once its climb has ended and added to its fit where the refined modes share the grid's
// mass: render-and-compare at the refined poses (engine/track/pose_shape.h), which the
// grid's hypotheses, up to half a spacing and a spin step off, cannot tell. Empty: none.
// Called from several threads at once: it must not change shared state.
using PoseTerm = std::function<double(const Rigid&)>;

struct Mode {
    std::array<double, 3> contact{};
    double probability = 0;
};

struct Estimate {
    std::array<double, 3> contact{};         // the Bayes contact: min expected distance, on the surface
    Rigid pose;                              // the most likely pose of the current touch (refined)
    std::array<double, 3> pose_contact{};    // where that pose's axis meets the surface
    std::vector<Rigid> window_poses;         // that pose carried to each touch of the window, oldest first
    std::vector<Mode> modes;                 // best first
    double mass_within_5mm = 0;              // the belief's mass within 5 mm of `contact`
    double fit = 0;                          // `pose`'s refined geometry fit (log; window_fit's measure)
    double pose_terms = 0;                   // the window's PoseTerms at `pose` and its window_poses (log; 0: none)
    std::vector<float> sample_belief;        // [S] summed over spins
};

class Tracker {
public:
    Tracker(rt::Context& ctx, Surface surface, FilterOptions options = {});
    // ctx null: every step runs on the ops' CPU references (the oracle; vtloc-bench times it).
    Tracker(rt::Context* ctx, Surface surface, FilterOptions options = {});
    // `like`'s surface and context under other options, no touches (with_options): the
    // surface, its tables and the registration's k-d tree shared with `like`, not built again.
    Tracker(const Tracker& like, FilterOptions options);
    // `like` under its own options with every step on the ops' CPU references, its surface and
    // host tables shared (vtloc check's oracle beside the GPU tracker; no touches).
    static Tracker cpu_reference_of(const Tracker& like);
    ~Tracker();
    Tracker(Tracker&&) noexcept;
    // What the constructor refuses, without a surface (callers check before building one).
    static void check_options(const FilterOptions& options);
    // How far the sensor can move between two touches of this object: its size, and each
    // touch's window centre within the press and kHopSlackMm of the surface, and six widths
    // of the odometry noise. A motion farther than this is refused (a unit mismatch or a
    // glitch: no pose fits it, and the belief would say nothing it could mean).
    static constexpr double kHopSlackMm = 5;
    double max_hop_mm() const;
    void check_motion(const Rigid& motion, size_t touch) const;  // check_rigid, then max_hop_mm
    Tracker(const Tracker&) = delete;
    Tracker& operator=(const Tracker&) = delete;

    // Online: the first touch takes no motion; each later one the motion from
    // the previous touch. term: a log field over the hypotheses [S * NS], or empty;
    // pose_term: the touch's evidence at the refined poses, or empty.
    void add_touch(const std::optional<Rigid>& motion, const std::vector<float>& term = {}, PoseTerm pose_term = {});
    // Forgets every touch (the object moved, a new grasp); the surface and the step graphs stay.
    void reset();
    int touches() const { return touches_; }
    const std::vector<float>& belief() const { return last_.prob; }  // [S * NS], sums to 1
    Estimate estimate() const;

    // Windowed (stateless): motions[i] from touch i to i + 1 (W - 1 of them),
    // terms[i] for touch i (empty vectors: none; or no terms at all); pose_terms likewise.
    Estimate evaluate_window(const std::vector<Rigid>& motions, const std::vector<std::vector<float>>& terms = {},
                             const std::vector<PoseTerm>& pose_terms = {});

    // The geometry fit (log) of a pose of the current touch given the window's
    // motions, refined from it as the estimate's modes are: the window's touches at
    // the tight widths plus the touch's own. Beside Estimate::fit it tells, where
    // the truth is known, a search that missed it (the truth fits better) from an
    // ambiguity (a wrong pose fits as well).
    double window_fit(const std::vector<Rigid>& motions, const Rigid& pose) const;

    const Surface& surface() const { return *surface_; }
    // What the tracker holds on the GPU now: the surface tables (resident; one copy for
    // the trackers made from one another, each counting it) and the arenas of the step
    // graphs built so far (one per window length); the CPU reference counts the same
    // bytes, as what the GPU would hold.
    uint64_t device_bytes() const;
    // Profiling (vtloc-bench): while on, each step's graph runs serially with GPU timestamps
    // (its executors are made again), and step_node_times() is the last step's time per node
    // (node name, ms); empty while off or without a GPU.
    void profile_steps(bool on);
    std::vector<std::pair<std::string, double>> step_node_times() const;
    // Checking (vtloc check --tracker): while on, each step keeps its inputs, so the last one
    // can be run again node by node against the CPU references (check::check_graph with
    // step_weights()); its graph is built at the first ask. Null while off or before a step.
    struct StepCase {
        Graph graph;
        std::map<std::string, HostTensor> inputs;
    };
    void capture_steps(bool on);
    const StepCase* last_step_case() const;
    const WeightStore& step_weights() const;
    // What it holds in host memory: the surface, its tables as the GPU reads them, and the
    // registration's tree and the pair search's index once a window has made them (the first
    // time one fits poorly). A tracker made by with_options shares these; each counts them.
    uint64_t host_bytes() const;
    const FilterOptions& options() const { return opt_; }
    // A heat-map over `cloud` [N, 3] or [N, >= 6] (point, outward normal): the belief of the
    // sample of each point's cell's nearest dense point (with normals: of the point on the
    // cloud point's own face, as a pose pressing it would read), min-max normalised.
    std::vector<float> heatmap(const Estimate& e, const HostTensor& cloud) const;

private:
    struct Impl;
    struct Step {
        std::vector<float> log, prob, marginal, cost;
        std::vector<Rigid> to_window;  // each earlier touch of the window in the current one's frame
    };
    // One GPU step over a window (motions between its touches, a term per touch or
    // null) and, optionally, the belief of the touch before it as a prior.
    Step run_step(const std::vector<Rigid>& motions, const std::vector<const std::vector<float>*>& terms,
                  const Rigid* prior_motion, const std::vector<float>* prior);
    void check_term(const std::vector<float>& term, size_t touch) const;
    void add_tables();      // the surface's tables the step graphs read
    void add_neighbours();  // the field slack's, where the options ask for it
    Estimate finish(const std::vector<float>& log, const std::vector<float>& marginal, const std::vector<float>& cost,
                    const std::vector<Rigid>& to_window, const std::vector<PoseTerm>& pose_terms) const;
    std::shared_ptr<const Surface> surface_;  // read-only: with_options' trackers share it
    FilterOptions opt_;
    std::unique_ptr<Impl> impl_;
    int touches_ = 0;
    Step last_;
    std::vector<Rigid> motions_;              // between the window's touches
    std::vector<std::vector<float>> terms_;   // the window's touch terms
    std::vector<PoseTerm> pose_terms_;        // and their pose terms
    std::vector<std::vector<float>> beliefs_; // log beliefs of the last W touches
    std::vector<float> prior_log_;
};

}  // namespace track
}  // namespace vtloc
