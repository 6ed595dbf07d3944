// vtloc eval --sequence: SPEC 6's multi-touch protocols on a dataset (docs/eval.md,
// "Several touches"). Windows of T touches along each object's collection tour
// end at the test touches whose order is at least 7 (the same touches for every
// T); the filter (api::Tracker, windowed form) sees the window's relative
// motions (touches.csv q..), optionally with seeded odometry noise, and, in the
// "+ network" rows, each touch's heat-map from the model.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <tuple>

#include "apps/vtloc/eval.h"
#include "engine/io/line_chart.h"
#include "apps/vtloc/report.h"
#include "base/atomic_write.h"
#include "base/error.h"

namespace vtloc::cli::eval {

namespace {

namespace fs = std::filesystem;
using P3 = std::array<double, 3>;

double dist(const P3& a, const P3& b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// The angle of Ra^T Rb in degrees.
double rotation_error_deg(const std::array<double, 9>& a, const std::array<double, 9>& b) {
    double tr = 0;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) tr += a[size_t(r * 3 + c)] * b[size_t(r * 3 + c)];
    return std::acos(std::clamp((tr - 1) / 2, -1.0, 1.0)) * 180 / M_PI;
}

// A motion with Gaussian noise: a rotation of N(0, deg) about each axis and N(0, mm) per axis.
api::Motion noisy(const api::Motion& m, double mm, double deg, std::mt19937_64& rng) {
    if (mm == 0 && deg == 0) return m;
    std::normal_distribution<double> g;
    const double w[3] = {g(rng) * deg * M_PI / 180, g(rng) * deg * M_PI / 180, g(rng) * deg * M_PI / 180};
    const double th = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    api::Motion d;
    if (th > 0) {
        const double k[3] = {w[0] / th, w[1] / th, w[2] / th}, c = std::cos(th), s = std::sin(th), v = 1 - c;
        d.R = {c + k[0] * k[0] * v,        k[0] * k[1] * v - k[2] * s, k[0] * k[2] * v + k[1] * s,
               k[1] * k[0] * v + k[2] * s, c + k[1] * k[1] * v,        k[1] * k[2] * v - k[0] * s,
               k[2] * k[0] * v - k[1] * s, k[2] * k[1] * v + k[0] * s, c + k[2] * k[2] * v};
    }
    d.t = {g(rng) * mm, g(rng) * mm, g(rng) * mm};
    return api::compose(m, d);
}

struct Score {
    double nd = 0, mm = 0, nd_sym = 0, nd_map = 0, nd_sym_map = 0, rot = 0, within5 = 0, mass5 = 0, cand_nd = 0;
    // Windows whose contact misses by more than 5 mm, by why: the true pose, refined, fits the
    // window's geometry better than the estimate's pose (search) or not (ambiguity).
    double miss_search = 0, miss_ambiguity = 0;
    int n = 0;
    void add(const Score& s) {
        nd += s.nd, mm += s.mm, nd_sym += s.nd_sym, nd_map += s.nd_map, nd_sym_map += s.nd_sym_map, rot += s.rot, within5 += s.within5, mass5 += s.mass5, cand_nd += s.cand_nd;
        miss_search += s.miss_search, miss_ambiguity += s.miss_ambiguity;
        n += s.n;
    }
    Score mean() const {
        Score m = *this;
        const double k = n ? 1.0 / n : 0;
        m.nd *= k, m.mm *= k, m.nd_sym *= k, m.nd_map *= k, m.nd_sym_map *= k, m.rot *= k, m.within5 *= k, m.mass5 *= k, m.cand_nd *= k;
        m.miss_search *= k, m.miss_ambiguity *= k;
        return m;
    }
};

struct RowKey {
    std::string method;  // "Geometry", "Geometry + network"
    bool noise;
    int T;
    bool operator<(const RowKey& o) const { return std::tie(method, noise, T) < std::tie(o.method, o.noise, o.T); }
};

constexpr double kSearchMargin = 1.0;  // nats: a true pose that fits better than this missed the search
constexpr const char* kRender = "Geometry + render-and-compare (MidasTouch-style)";
constexpr const char* kOracle = "Geometry + render-and-compare (oracle maps)";

std::vector<int> parse_ts(const std::string& v) {
    std::vector<int> out;
    std::stringstream ss(v);
    std::string item;
    while (std::getline(ss, item, ',')) {
        char* end = nullptr;
        long t = std::strtol(item.c_str(), &end, 10);
        if (item.empty() || *end || t < 1 || t > 8) throw UsageError("--sequence takes window lengths 1..8, e.g. 1,2,3,4,6,8; got '" + v + "'");
        out.push_back(int(t));
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

}  // namespace

void plot_sequence(const std::string& path, const nlohmann::json& rows, const std::string& data) {
    io::LineChart chart;
    chart.title = "ND against the number of touches (" + data + ", all objects, surface protocol)";
    chart.x_label = "touches T (the window ending at each test touch)";
    chart.y_label = "ND (%)";
    chart.width = 1300;  // room for the legend's longest method name beside the plot
    std::vector<int> Ts;
    for (const nlohmann::json& r : rows) Ts.push_back(r.at("T").get<int>());
    std::sort(Ts.begin(), Ts.end());
    Ts.erase(std::unique(Ts.begin(), Ts.end()), Ts.end());
    if (Ts.empty()) throw api::Error(path + ": the report has no rows to plot");
    for (int T : Ts) chart.x.push_back(T);
    std::vector<std::string> order;  // methods in the report's order, each with its ND and ND up to symmetry
    std::map<std::string, std::pair<std::vector<double>, std::vector<double>>> lines;
    for (const nlohmann::json& r : rows) {
        if (r.at("subset") != "all") continue;
        const std::string name = r.at("method").get<std::string>() + (r.at("odometry_noise").get<bool>() ? ", noise" : "");
        if (!lines.count(name)) order.push_back(name);
        auto& [nd, sym] = lines[name];
        nd.resize(Ts.size(), NAN), sym.resize(Ts.size(), NAN);
        const size_t i = size_t(std::find(Ts.begin(), Ts.end(), r.at("T").get<int>()) - Ts.begin());
        nd[i] = r.at("nd").get<double>(), sym[i] = r.at("nd_symmetry").get<double>();
    }
    for (size_t k = 0; k < order.size(); ++k) {  // one colour per method: solid ND, dashed up to symmetry
        chart.series.push_back({order[k], lines[order[k]].first, false, int(k)});
        chart.series.push_back({"  up to symmetry", lines[order[k]].second, true, int(k)});
    }
    io::save_line_chart_png(path, chart);
    std::printf("wrote     %s\n", path.c_str());
}

int run_sequence(Session& s, const Args& a) {
    // The single-touch report's options have no meaning here; say so rather than ignore them.
    refuse_other_report(a, OptionFor::sequence);
    const std::string data = a.required("--data");
    const std::vector<int> Ts = parse_ts(a.get("--sequence").value_or("1,2,3,4,6,8"));
    const bool geometry_only = a.flag("--geometry-only");
    std::optional<std::pair<double, double>> noise;
    if (auto v = a.get("--odometry-noise")) {
        std::vector<double> n = parse_numbers(*v, 2, "--odometry-noise");
        if (!(n[0] >= 0 && n[1] >= 0)) throw UsageError("--odometry-noise MM,DEG must be >= 0");
        noise = std::make_pair(n[0], n[1]);
    }
    const std::string objects = a.get("--objects").value_or("all");
    if (objects != "all" && objects != "known" && objects != "unknown") throw UsageError("--objects must be all, known or unknown");
    const sim::Dataset d = [&] {
        try {
            return sim::read_dataset(data);
        } catch (const vtloc::Error& e) {
            throw api::Error(e.what());
        }
    }();
    api::TrackerOptions to;
    // online_window=W: each window's touches go through add_touch one by one (the online form,
    // the last W scored exactly, older ones through the prior) instead of evaluate_window.
    int online_window = 0;
    // --filter k=v,...: the filter's knobs, for fitting them on windows that end at train touches.
    if (auto f = a.get("--filter")) {
        std::stringstream ss(*f);
        std::string kv;
        while (std::getline(ss, kv, ',')) {
            const size_t eq = kv.find('=');
            if (eq == std::string::npos) throw UsageError("--filter takes key=value pairs, got '" + kv + "'");
            const std::string k = kv.substr(0, eq);
            // render_refined_floor=none: no floor (-inf, which parse_numbers refuses).
            const double v = k == "render_refined_floor" && kv.substr(eq + 1) == "none"
                                 ? -INFINITY
                                 : parse_numbers(kv.substr(eq + 1), 1, "--filter " + k)[0];
            if (k == "press") to.press_mm = v;
            else if (k == "sigma_d") to.sigma_d_mm = v;
            else if (k == "sigma_a") to.sigma_a_deg = v;
            else if (k == "allowance") to.grid_allowance = v;
            else if (k == "refine_widen") to.refine_widen = v;
            else if (k == "refine_reach") to.refine_reach_mm = v;
            else if (k == "rescue_fit") to.rescue_fit = v;
            else if (k == "rescue_modes") to.rescue_modes = int(v);
            else if (k == "register") {
                if (!(v >= 0 && v <= 64) || v != std::floor(v)) throw UsageError("--filter: register is an integer in [0, 64] (0: off)");
                to.register_rounds = int(v);
            }
            else if (k == "deep_fit") to.deep_fit = v;
            else if (k == "pair_modes") {
                if (!(v >= 0 && v <= 64) || v != std::floor(v)) throw UsageError("--filter: pair_modes is an integer in [0, 64] (0: off)");
                to.pair_modes = int(v);
            } else if (k == "deep_modes") {
                if (!(v >= 0 && v <= 64) || v != std::floor(v)) throw UsageError("--filter: deep_modes is an integer in [0, 64] (0: off)");
                to.deep_modes = int(v);
            }
            else if (k == "free_space") to.free_space_mm = v;
            else if (k == "network_weight") to.network_weight = v;
            else if (k == "render_weight") to.render_weight = v;
            else if (k == "render_press_percentile") to.render_press_percentile = v;
            else if (k == "render_cell_mm") to.render_cell_mm = v;
            else if (k == "render_refined_weight") to.render_refined_weight = v;
            else if (k == "render_refined_floor") to.render_refined_floor = v;
            else if (k == "render_slack_rounds") to.render_slack_rounds = int(v);
            else if (k == "field_slack") {
                if (v != 0 && v != 1) throw UsageError("--filter: field_slack is 0 or 1");
                to.field_slack = v == 1;
            }
            else if (k == "render_quadratic") {
                if (v != 0 && v != 1) throw UsageError("--filter: render_quadratic is 0 or 1");
                to.render_quadratic = v == 1;
            }
            else if (k == "hypotheses") to.hypotheses = int64_t(v);
            else if (k == "n_spin") to.n_spin = int(v);
            else if (k == "online_window") {
                if (!(v >= 1 && v <= 64) || v != std::floor(v)) throw UsageError("--filter: online_window is an integer in [1, 64]");
                online_window = int(v), to.window = int(v);
            }
            else throw UsageError("--filter: unknown knob '" + k + "' (press, sigma_d, sigma_a, allowance, refine_widen, refine_reach, rescue_fit, rescue_modes, register, deep_fit, deep_modes, pair_modes, free_space, network_weight, render_weight, render_quadratic, render_press_percentile, render_cell_mm, render_refined_weight, render_refined_floor, render_slack_rounds, field_slack, hypotheses, n_spin, online_window)");
        }
    }
    const std::string end_split = a.get("--end-split").value_or("test");
    if (end_split != "test" && end_split != "train") throw UsageError("--end-split must be test or train");
    std::optional<api::Model> model;
    std::string model_path;
    if (!geometry_only) {
        model_path = a.get("--model").value_or(default_model_path());
        model.emplace(load_model(s, model_path, api::Backend::Gpu));
    }
    const bool render_compare = a.flag("--render-compare");
    // --rows: only these rows (fitting a knob needs only the rows it moves).
    const std::set<std::string> all_rows{"geometry", "network", "network-test", "render", "oracle"};
    std::set<std::string> rows_wanted = all_rows;
    if (auto r = a.get("--rows")) {
        rows_wanted.clear();
        std::stringstream ss(*r);
        std::string item;
        while (std::getline(ss, item, ',')) {
            if (!all_rows.count(item)) {
                std::string names;
                for (const std::string& n : all_rows) names += (names.empty() ? "" : ", ") + n;
                throw UsageError("--rows takes " + names + "; got '" + item + "'");
            }
            rows_wanted.insert(item);
        }
    }
    std::optional<api::GelShapeReader> reader;
    if (render_compare) reader.emplace(s.gpu(), api::GelShapeOptions::rendered_frames());
    std::map<RowKey, std::map<std::string, Score>> per_object;  // row -> object -> sum
    std::map<std::string, std::string> subset_of;
    int windows = 0;
    // --per-touch: one line per window and row (the report's means hide which windows missed).
    std::string per_window = "object,subset,touch,order,T,method,odometry_noise,error_mm,nd,nd_symmetry,rotation_deg,missed,nd_candidates\n";
    for (const sim::ObjectRecord& o : d.objects) {
        if (objects == "known" && o.object_split != "seen") continue;
        if (objects == "unknown" && o.object_split != "unseen") continue;
        const std::string mesh = (fs::path(o.folder) / "mesh.ply").string();
        if (!fs::exists(mesh)) throw api::Error(mesh + ": missing (the surface protocol needs each object's mesh)");
        subset_of[o.name] = o.subset;
        api::Tracker clean(s.gpu(), mesh, to);
        // With noise, the filter is told the robot's odometry accuracy (a robot's stated spec, not a
        // fitted knob): its widths grow with the steps and the lever arm (SPEC 6).
        std::optional<api::Tracker> noisy_tracker;
        api::TrackerOptions tn = to;
        if (noise) {
            tn.odometry_mm = noise->first, tn.odometry_deg = noise->second;
            noisy_tracker.emplace(clean.with_options(tn));  // the same surface: not built again
        }
        // The candidates protocol (the paper's): hypotheses only at the object's candidates S^c, the
        // contacts of the split the windows end at (the test contacts; with --end-split train the
        // train ones), so that the truth is among them as the protocol assumes.
        std::vector<std::array<double, 3>> cand_points;
        for (const sim::TouchRecord* t : o.touches_of(end_split)) cand_points.push_back(t->contact);
        api::TrackerOptions tc = to, tcn = tn;
        tc.candidates = tcn.candidates = cand_points;
        api::Tracker cand_clean(s.gpu(), mesh, tc);
        std::optional<api::Tracker> cand_noisy;
        if (noise) cand_noisy.emplace(cand_clean.with_options(tcn));
        std::vector<const sim::TouchRecord*> tour;
        for (const sim::TouchRecord& t : o.touches)
            if (t.order >= 0) tour.push_back(&t);
        std::sort(tour.begin(), tour.end(), [](auto* x, auto* y) { return x->order < y->order; });
        for (size_t i = 0; i < tour.size(); ++i)
            if (tour[i]->order != int(i))
                throw api::Error(o.folder + "/touches.csv: the collection order skips " + std::to_string(i));
        // Each motion of the tour checked against the object before any window (the filter refuses
        // a hop no two touches on it can make): named by the file and the touch's id.
        for (size_t i = 1; i < tour.size(); ++i) {
            try {
                clean.check_motion(api::Motion{tour[i]->rel_R, tour[i]->rel_t}, tour[i]->order + 1);
            } catch (const api::Error& e) {
                throw api::Error(o.folder + "/touches.csv, id " + std::to_string(tour[i]->id) + " (the tour's touch " +
                                 std::to_string(tour[i]->order + 1) + "): " + e.what());
            }
        }
        std::optional<api::Object> encoded;
        std::map<size_t, api::TouchResult> results;
        // (hypothesis set: 0 surface, 1 candidates; row; tour index) -> that touch's term.
        std::map<std::tuple<int, std::string, size_t>, std::vector<float>> term_cache;
        // Render-and-compare: each touch's gel shape read from its frame, and the renderer's own
        // indentation map (the oracle) where the dataset has them.
        std::map<size_t, api::GelShape> measured, oracle;
        std::optional<api::TactileImage> empty_frame;
        const bool has_oracle = render_compare && !tour.empty() &&
                                fs::exists(fs::path(image_path(o, *tour[0])).replace_extension(".depth.png"));
        if (render_compare) empty_frame = api::load_tactile_image((fs::path(o.folder) / "background.png").string());
        if (model) {
            api::PointCloud cloud;
            for (int64_t i = 0; i < o.points.shape[0]; ++i)
                for (int k = 0; k < 3; ++k)
                    cloud.xyz.push_back(o.points.data[size_t(6 * i + k)]), cloud.normals.push_back(o.points.data[size_t(6 * i + 3 + k)]);
            std::vector<float> cand = o.candidates().data;
            encoded = model->encode_object(cloud, cand);
        }
        for (size_t end = 7; end < tour.size(); ++end) {
            if (tour[end]->split != end_split) continue;
            // Windows end later and later: terms of touches before the longest window's start go.
            const size_t longest = size_t(*std::max_element(Ts.begin(), Ts.end())), first = end + 1 > longest ? end + 1 - longest : 0;
            for (auto it = term_cache.begin(); it != term_cache.end();)
                it = std::get<2>(it->first) < first ? term_cache.erase(it) : std::next(it);
            const sim::TouchRecord& truth = *tour[end];
            for (bool with_noise : {false, true}) {
                if (with_noise && !noise) continue;
                // One noise draw per motion, the same for every T (seeded by object and touch).
                std::vector<api::Motion> all;
                for (size_t i = 1; i <= end; ++i) {
                    std::mt19937_64 rng(std::hash<std::string>{}(o.name) ^ (uint64_t(tour[i]->id) * 0x9E3779B97F4A7C15ULL));
                    api::Motion m{tour[i]->rel_R, tour[i]->rel_t};
                    all.push_back(with_noise ? noisy(m, noise->first, noise->second, rng) : m);
                }
                api::Tracker& tracker = with_noise ? *noisy_tracker : clean;
                api::Tracker& cand_tracker = with_noise ? *cand_noisy : cand_clean;
                for (int T : Ts) {
                    std::vector<api::Motion> motions(all.end() - (T - 1), all.end());
                    // The truth's geometry fit is the same for every row of this window: once, when a row misses.
                    std::optional<double> truth_fit;
                    // The third row drops the network term of the window's train frames, which a
                    // trained model has seen (SPEC 6): only test frames speak for themselves.
                    for (const char* method : {"Geometry", "Geometry + network", "Geometry + network (test frames)", kRender, kOracle}) {
                        const bool rc = std::string(method) == kRender, orc = std::string(method) == kOracle;
                        const bool net = std::string(method) != "Geometry" && !rc && !orc;
                        const bool test_only = std::string(method) == "Geometry + network (test frames)";
                        if (net && !model) continue;
                        if ((rc && !render_compare) || (orc && !has_oracle)) continue;
                        const std::string row_name = rc ? "render" : orc ? "oracle" : test_only ? "network-test" : net ? "network" : "geometry";
                        if (!rows_wanted.count(row_name)) continue;
                        // Each touch's term once per row and hypothesis set (the clean and the noisy filter
                        // share theirs): a touch sits in up to 8 windows.
                        // The touch's gel shape in the render-and-compare rows (read once), else null.
                        auto shape_of = [&](size_t i) -> const api::GelShape* {
                            if (!rc && !orc) return nullptr;
                            auto& cache = rc ? measured : oracle;
                            if (!cache.count(i)) {
                                const std::string img = image_path(o, *tour[i]);
                                cache[i] = rc ? read_gel_shape(*reader, img, api::load_tactile_image(img), &*empty_frame,
                                                               (fs::path(o.folder) / "background.png").string())
                                              : api::load_indentation(fs::path(img).replace_extension(".depth.png").string(), d.sensor.mm_per_px);
                            }
                            return &cache[i];
                        };
                        std::vector<const api::GelShape*> shapes;
                        if (rc || orc)
                            for (size_t i = end + 1 - size_t(T); i <= end; ++i) shapes.push_back(shape_of(i));
                        auto window_terms = [&](api::Tracker& scorer, int set) {
                            std::vector<std::vector<float>> terms;
                            for (size_t i = end + 1 - size_t(T); i <= end; ++i) {
                                const auto key = std::make_tuple(set, row_name, i);
                                auto it = term_cache.find(key);
                                if (it == term_cache.end()) {
                                    const api::GelShape* g = shape_of(i);
                                    const api::TouchResult* r = nullptr;
                                    if (net && !(test_only && tour[i]->split != "test")) {
                                        if (!results.count(i))
                                            results[i] = model->localize(*encoded, api::load_tactile_image(image_path(o, *tour[i])));
                                        r = &results[i];
                                    }
                                    it = term_cache.emplace(key, scorer.touch_term(r, net ? &*encoded : nullptr, g)).first;
                                }
                                terms.push_back(it->second);
                            }
                            return terms;
                        };
                        // The windowed form, or the online one touch by touch.
                        auto run = [&](api::Tracker& t, const std::vector<std::vector<float>>& terms) {
                            if (!online_window) return t.evaluate_window_terms(motions, terms, shapes);
                            t.reset();
                            for (size_t i = 0; i < terms.size(); ++i)
                                t.add_touch_term(i ? std::optional<api::Motion>(motions[i - 1]) : std::nullopt, terms[i],
                                                 shapes.empty() ? nullptr : shapes[i]);
                            return t.estimate();
                        };
                        const api::TrackerEstimate e = run(tracker, window_terms(clean, 0));
                        Score sc;
                        sc.n = 1;
                        sc.mm = dist(e.contact, truth.contact);
                        sc.nd = 100 * sc.mm / o.diameter_mm;
                        // Up to symmetry, the Bayes estimate of that metric: the belief's expected
                        // distance to each candidate answer counted to the nearest image.
                        P3 sym_pick = e.contact;
                        if (!o.symmetry.none()) {
                            const std::vector<float> sp = tracker.sample_points();
                            std::vector<size_t> live;
                            for (size_t k = 0; k < e.sample_belief.size(); ++k)
                                if (e.sample_belief[k] > 1e-5f) live.push_back(k);
                            std::vector<P3> answers{e.contact, e.pose_contact};
                            for (const auto& md : e.modes) answers.push_back(md.contact);
                            for (size_t k : live) answers.push_back(P3{sp[3 * k], sp[3 * k + 1], sp[3 * k + 2]});
                            if (answers.size() > 400) answers.resize(400);
                            double best_r = INFINITY;
                            for (const P3& c : answers) {
                                double r = 0;
                                for (size_t k : live)
                                    r += e.sample_belief[k] * sim::distance_up_to_symmetry(o.symmetry, c, P3{sp[3 * k], sp[3 * k + 1], sp[3 * k + 2]});
                                if (r < best_r) best_r = r, sym_pick = c;
                            }
                        }
                        sc.nd_sym = 100 * sim::distance_up_to_symmetry(o.symmetry, sym_pick, truth.contact) / o.diameter_mm;
                        sc.nd_map = 100 * dist(e.pose_contact, truth.contact) / o.diameter_mm;
                        sc.nd_sym_map = 100 * sim::distance_up_to_symmetry(o.symmetry, e.pose_contact, truth.contact) / o.diameter_mm;
                        sc.rot = rotation_error_deg(e.pose.R, truth.R);
                        sc.within5 = sc.mm <= 5 ? 1 : 0;
                        sc.mass5 = e.mass_within_5mm;
                        if (sc.mm > 5) {
                            // A margin of 1 nat: the refinement's own last step changes the fit by less.
                            if (!truth_fit) truth_fit = tracker.window_fit(motions, api::Motion{truth.R, truth.t});
                            (*truth_fit > e.fit + kSearchMargin ? sc.miss_search : sc.miss_ambiguity) = 1;
                        }
                        // Candidates protocol: the belief over the candidates' poses alone; the answer is the
                        // candidate of least expected distance under it.
                        const api::TrackerEstimate ec = run(cand_tracker, window_terms(cand_clean, 1));
                        double best = INFINITY;
                        P3 pick{};
                        for (size_t c = 0; c < cand_points.size(); ++c) {
                            double r = 0;
                            for (size_t k = 0; k < cand_points.size(); ++k) r += ec.sample_belief[k] * dist(cand_points[c], cand_points[k]);
                            if (r < best) best = r, pick = cand_points[c];
                        }
                        sc.cand_nd = 100 * dist(pick, truth.contact) / o.diameter_mm;
                        per_object[{method, with_noise, T}][o.name].add(sc);
                        ++windows;
                        char line[512];
                        std::snprintf(line, sizeof line, "%s,%s,%d,%d,%d,%s,%s,%.4f,%.4f,%.4f,%.3f,%s,%.4f\n", o.name.c_str(), o.subset.c_str(),
                                      truth.id, truth.order, T, method, with_noise ? "yes" : "no", sc.mm, sc.nd, sc.nd_sym, sc.rot,
                                      sc.miss_search ? "search" : sc.miss_ambiguity ? "ambiguity" : "", sc.cand_nd);
                        per_window += line;
                    }
                }
            }
        }
        // device_bytes counts the codebook too where render-and-compare is on (most of it then).
        std::printf("object    %-14s %s, spacing %.2f mm, %zu tour touches, on the GPU %.1f MiB%s\n", o.name.c_str(),
                    o.subset.c_str(), clean.spacing_mm(), tour.size(), double(clean.device_bytes()) / 1048576.0,
                    render_compare ? " (surface tables and codebook)" : " (surface tables)");
        std::fflush(stdout);
    }
    if (per_object.empty()) throw api::Error(data + ": no test touch with order >= 7 to end a window at");

    // Per object, then over objects, per subset.
    std::string md = "| method | odometry noise | T | subset | objects | ND % (surface) | mm | ND % up to symmetry | ND % (candidates) | rotation deg | within 5 mm | belief mass within 5 mm | missed: search | missed: ambiguity |\n"
                     "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
    nlohmann::json rows = nlohmann::json::array();
    std::printf("\n%-34s %-6s %2s %-12s %7s %7s %7s %7s %7s %7s %7s %7s %7s\n", "method", "noise", "T", "subset", "ND%", "mm", "symND%",
                "candND%", "rot", "in5mm", "mass5", "search", "ambig");
    for (const auto& [key, objs] : per_object)
        for (const char* subset : {"non-uniform", "uniform", "all"}) {
            Score acc;
            int n_obj = 0;
            for (const auto& [name, sc] : objs) {
                if (std::string(subset) != "all" && subset_of[name] != subset) continue;
                Score m = sc.mean();
                m.n = 1;
                acc.add(m);
                ++n_obj;
            }
            if (!n_obj) continue;
            const Score m = acc.mean();
            const std::string nz = key.noise ? "yes" : "no";
            std::printf("%-34s %-6s %2d %-12s %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f\n", key.method.c_str(), nz.c_str(), key.T,
                        subset, m.nd, m.mm, m.nd_sym, m.cand_nd, m.rot, m.within5, m.mass5, m.miss_search, m.miss_ambiguity);
            char line[512];
            std::snprintf(line, sizeof line, "| %s | %s | %d | %s | %d | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |\n",
                          key.method.c_str(), nz.c_str(), key.T, subset, n_obj, m.nd, m.mm, m.nd_sym, m.cand_nd, m.rot, m.within5, m.mass5,
                          m.miss_search, m.miss_ambiguity);
            md += line;
            rows.push_back({{"method", key.method}, {"odometry_noise", key.noise}, {"T", key.T}, {"subset", subset},
                            {"objects", n_obj}, {"nd", m.nd}, {"mm", m.mm}, {"nd_symmetry", m.nd_sym}, {"nd_pose", m.nd_map}, {"nd_pose_symmetry", m.nd_sym_map}, {"nd_candidates", m.cand_nd},
                            {"rotation_deg", m.rot}, {"within_5mm", m.within5}, {"mass_within_5mm", m.mass5},
                            {"missed_search", m.miss_search}, {"missed_ambiguity", m.miss_ambiguity}});
        }
    nlohmann::json per_obj = nlohmann::json::object();
    for (const auto& [key, objs] : per_object)
        for (const auto& [name, sc] : objs) {
            const Score m = sc.mean();
            per_obj[key.method + (key.noise ? " (noise)" : "") + " T" + std::to_string(key.T)][name] = {{"nd", m.nd}, {"nd_symmetry", m.nd_sym}, {"nd_pose", m.nd_map}, {"nd_pose_symmetry", m.nd_sym_map}, {"mm", m.mm}, {"touches", sc.n},
                                                                                                   {"missed_search", m.miss_search}, {"missed_ambiguity", m.miss_ambiguity}};
        }
    std::printf("\nwindows   %d (ending at the %s touches with order >= 7; the candidates protocol over the %s touches' contacts)\n",
                windows, end_split.c_str(), end_split.c_str());
    if (auto p = a.get("--markdown")) write_file_atomic(*p, md), std::printf("wrote     %s\n", p->c_str());
    if (auto p = a.get("--per-touch")) write_file_atomic(*p, per_window), std::printf("wrote     %s\n", p->c_str());
    if (auto p = a.get("--plot")) plot_sequence(*p, rows, data);
    if (auto p = a.get("--json")) {
        nlohmann::json j{{"format", "vtloc-eval-sequence/1"}, {"data", data}, {"model", geometry_only ? "" : model_path},
                         {"rows", rows}, {"per_object", per_obj}};
        write_file_atomic(*p, j.dump(1) + "\n");
        std::printf("wrote     %s\n", p->c_str());
    }
    return 0;
}

}  // namespace vtloc::cli::eval
