// vtloc eval: the paper's metrics for a weight file on a dataset (docs/eval.md).
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <filesystem>
#include <set>

#include "apps/vtloc/eval.h"
#include "apps/vtloc/report.h"
#include "base/error.h"

namespace vtloc::cli {

namespace {

namespace fs = std::filesystem;

const char* kHelp =
    "usage: vtloc eval [--model M] --data DIR [options]\n"
    "\n"
    "The paper's metrics (mm Error, ND, Top-1, Top-5, MPE; docs/eval.md) of a weight file on a\n"
    "dataset in the layout of docs/dataset.md, per subset (non-uniform / uniform / all),\n"
    "averaged per object and then over objects, with the Chance, Point Filtering and Codebook\n"
    "(render-and-compare alone, MidasTouch-style) baselines.\n"
    "Each object is encoded once with its candidates (its test contacts); its touches run in\n"
    "batches.\n"
    "\n"
    "  --model M                 weight file (default: the shipped models/vtloc-lite-everyday)\n"
    "  --data DIR                dataset folder (dataset.json, objects/...)\n"
    "  --split test|train|all    which touches (default test)\n"
    "  --objects all|known|unknown\n"
    "                            all objects (default), the trained-on ones (object_split seen)\n"
    "                            or the never-trained ones (unseen)\n"
    "  --iters N                 ILU iterations, 0..64 (default: the model's)\n"
    "  --topk K                  K of the heat-map that MPE scores, capped at the candidate count\n"
    "                            (default 5)\n"
    "  --sequence T[,T..]        several touches (SPEC section 6): windows of T touches along each\n"
    "                            object's collection tour ending at the test touches with order >= 7,\n"
    "                            through the multi-touch filter with the dataset's relative motions;\n"
    "                            both protocols (surface, candidates), rows for geometry alone and\n"
    "                            geometry + the model's heat-map (e.g. 1,2,3,4,6,8; needs mesh.ply)\n"
    "  --geometry-only           with --sequence: no network rows (no model needed)\n"
    "  --render-compare          with --sequence: rows for geometry + render-and-compare (SPEC 9): each\n"
    "                            frame's gel shape (against the object's background.png) scored against\n"
    "                            what every hypothesis would press (\"MidasTouch-style\"), and, where the\n"
    "                            dataset has vtloc synth --indentation maps, the same on those (oracle)\n"
    "  --rows R,...              with --sequence: only these rows of geometry, network, network-test,\n"
    "                            render, oracle (default: every row the other options ask for)\n"
    "  --odometry-noise MM,DEG   with --sequence: also rows with seeded Gaussian noise on every motion\n"
    "  --filter K=V,...          with --sequence: the filter's knobs (press, sigma_d, sigma_a, allowance,\n"
    "                            refine_widen, refine_reach, rescue_fit, rescue_modes, register, deep_fit,\n"
    "                            deep_modes, pair_modes, free_space, network_weight, render_weight, render_quadratic,\n"
    "                            render_press_percentile, render_cell_mm, render_refined_weight,\n"
    "                            render_refined_floor (none: off), render_slack_rounds, field_slack,\n"
    "                            hypotheses, n_spin;\n"
    "                            online_window=W: the online form, touch by touch); fit them with\n"
    "                            --end-split train\n"
    "  --end-split test|train    with --sequence: windows end at test touches (default) or train ones\n"
    "  --plot FILE.png           with --sequence: ND (solid) and ND up to symmetry (dashed) against T, all\n"
    "                            objects, a colour per method and noise\n"
    "  --replot REPORT.json      with --plot, no --data: redraw the plot of a saved --sequence report\n"
    "  --cloud full|xyz|view     the object cloud: points.csv with its normals (default), its points\n"
    "                            with estimated normals (xyz), or the single view a depth camera sees\n"
    "                            (view.xyz of vtloc synth --view; estimated normals facing the camera)\n"
    "  --json FILE               the report as JSON (vtloc-eval/1)\n"
    "  --markdown FILE           the table as markdown\n"
    "  --per-touch FILE.csv      object, touch, subset, error_mm, nd, rank, mpe per touch; with\n"
    "                            --sequence one line per window and row (error, ND, up to symmetry,\n"
    "                            rotation, missed by search or ambiguity, candidates protocol)\n"
    "  --render DIR              heat-map pictures of the k worst and k best touches\n"
    "  --render-count k          k for --render (default 3)\n"
    "  --skip-bad                evaluate the touches that can be read; report the others\n"
    "  --no-baselines            leave out the Chance, Point Filtering and Codebook rows\n"
    "  --backend gpu|cpu         Vulkan (default) or the plain C++ reference ops\n"
    "  --mm-per-px MM            the frames' pixel size in mm (default: the dataset's sensor.mm_per_px);\n"
    "                            frames are rescaled to the model's sensor pixel size before the crop\n"
    "                            when it differs (models that record no sensor: never, unless given)\n"
    "\n"
    "Chance is exact (every candidate taken as the prediction once). Point Filtering and Codebook\n"
    "need mesh.ply in every object folder and are skipped with a note otherwise. Exit status: 0 ok,\n"
    "1 bad input or runtime error, 2 usage error.\n";

// Sim-library errors as the CLI's one-line errors.
template <class F>
auto sim_call(F&& f) {
    try {
        return f();
    } catch (const vtloc::Error& e) {
        throw api::Error(e.what());
    }
}

std::string one_of(const Args& a, const std::string& name, const std::string& fallback,
                   std::initializer_list<const char*> allowed) {
    std::string v = a.get(name).value_or(fallback), list;
    for (const char* x : allowed) {
        if (v == x) return v;
        list += std::string(list.empty() ? "" : ", ") + x;
    }
    throw UsageError(name + " must be one of " + list + ", got '" + v + "'");
}

eval::Options parse(const Args& a) {
    eval::Options o;
    o.data = a.required("--data");
    o.model = a.get("--model").value_or("");
    o.split = one_of(a, "--split", "test", {"test", "train", "all"});
    o.objects = one_of(a, "--objects", "all", {"all", "known", "unknown"});
    o.iters = a.integer("--iters", -1, 0, api::kMaxIterations);
    o.topk = a.integer("--topk", 5, 1, api::kMaxTopK);
    o.cloud = one_of(a, "--cloud", "full", {"full", "xyz", "view"});
    o.json = a.get("--json");
    o.markdown = a.get("--markdown");
    o.per_touch = a.get("--per-touch");
    o.render_dir = a.get("--render");
    if (a.flag("--render-count") && !o.render_dir) throw UsageError("--render-count needs --render DIR");
    o.render_count = a.integer("--render-count", 3, 1, 1000);
    o.skip_bad = a.flag("--skip-bad");
    o.baselines = !a.flag("--no-baselines");
    const std::string backend = one_of(a, "--backend", "gpu", {"gpu", "cpu"});
    o.backend = backend == "gpu" ? api::Backend::Gpu : api::Backend::Cpu;
    o.mm_per_px = mm_per_px_option(a);
    return o;
}

bool wanted(const sim::TouchRecord& t, const std::string& split) {
    return split == "all" ? (t.split == "train" || t.split == "test") : t.split == split;
}

// The objects and touches the options select; missing images are found here,
// before any engine work (skipped with --skip-bad, else an error).
std::vector<eval::Job> select(const sim::Dataset& d, const eval::Options& opt, const api::ModelInfo& info,
                              std::vector<eval::Skip>& skips) {
    const std::string index = (fs::path(d.root) / "dataset.json").string();
    std::vector<eval::Job> jobs;
    for (const sim::ObjectRecord& o : d.objects) {
        if (opt.objects == "known" && o.object_split != "seen") continue;
        if (opt.objects == "unknown" && o.object_split != "unseen") continue;
        eval::Job job;
        job.rec = &o;
        const std::string points = (fs::path(o.folder) / "points.csv").string();
        if (o.points.shape.size() != 2 || o.points.shape[0] != info.sample_points)
            throw api::Error(points + ": " + std::to_string(o.points.shape.empty() ? 0 : o.points.shape[0]) +
                             " points, the model takes " + std::to_string(info.sample_points));
        try {
            job.geom = sim::MetricObject::make(o.points, o.candidates());
        } catch (const vtloc::Error& e) {
            throw api::Error(points + ": " + e.what());
        }
        job.topk = std::min<int>(opt.topk, int(job.geom.candidates.size()));
        for (const sim::TouchRecord& t : o.touches) {
            if (!wanted(t, opt.split)) continue;
            const std::string path = eval::image_path(o, t);
            std::error_code ec;
            if (!fs::is_regular_file(path, ec)) {
                const std::string why = fs::exists(path, ec) ? "not a file" : "no such file";
                if (!opt.skip_bad)
                    throw api::Error(path + ": " + why + " (touch " + std::to_string(t.id) + " of '" + o.name +
                                     "'; --skip-bad evaluates the rest)");
                skips.push_back({o.name, t.id, path, why});
                continue;
            }
            job.touches.push_back(&t);
        }
        jobs.push_back(std::move(job));
    }
    if (jobs.empty())
        throw api::Error(index + ": no object with object_split '" + std::string(opt.objects == "known" ? "seen" : "unseen") +
                         "' (--objects " + opt.objects + ")");
    return jobs;
}

// "skipped 2 of 40 touches (--skip-bad): 2 no such file (e.g. .../0003.png)".
std::string skip_summary(const std::vector<eval::Skip>& skips, size_t total) {
    std::vector<std::pair<std::string, std::pair<int, std::string>>> by_reason;
    for (const eval::Skip& s : skips) {
        auto it = std::find_if(by_reason.begin(), by_reason.end(), [&](auto& r) { return r.first == s.reason; });
        if (it == by_reason.end()) by_reason.push_back({s.reason, {1, s.file}});
        else ++it->second.first;
    }
    std::string out = "skipped " + std::to_string(skips.size()) + " of " + std::to_string(total) + " touches (--skip-bad):";
    for (size_t i = 0; i < by_reason.size(); ++i)
        out += std::string(i ? ";" : "") + " " + std::to_string(by_reason[i].second.first) + " " + by_reason[i].first +
               " (e.g. " + by_reason[i].second.second + ")";
    return out;
}

void render_extremes(const eval::Options& opt, const eval::MethodResult& model, const std::vector<eval::Job>& jobs,
                     const std::string& config, std::vector<std::string>& written) {
    make_folder(*opt.render_dir);
    std::vector<size_t> order(model.rows.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return model.rows[a].m.error_mm < model.rows[b].m.error_mm; });
    const size_t n_best = std::min<size_t>(size_t(opt.render_count), order.size());
    const size_t n_worst = std::min<size_t>(size_t(opt.render_count), order.size() - n_best);
    auto render = [&](size_t row_index, const std::string& kind, size_t k) {
        const eval::TouchRow& r = model.rows[row_index];
        const sim::ObjectRecord& o = *jobs[r.job].rec;
        const api::TactileImage image = api::load_tactile_image(eval::image_path(o, *r.touch));
        api::RenderOptions ro;
        ro.contact = r.contact;
        ro.ground_truth = r.touch->contact;
        ro.tactile = &image;
        char caption[256];
        std::snprintf(caption, sizeof caption, "%s: %s touch %d, error %.2f mm, rank %d%s", config.c_str(),
                      o.name.c_str(), r.touch->id, r.m.error_mm, r.m.rank, "");
        ro.caption = caption;
        char name[64];
        std::snprintf(name, sizeof name, "%s_%02zu_", kind.c_str(), k + 1);
        const std::string path =
            (fs::path(*opt.render_dir) / (name + o.name + "_" + std::to_string(r.touch->id) + ".png")).string();
        api::render_heatmap_png(path, model.encoded[r.job], r.heat, ro);
        written.push_back(path);
    };
    for (size_t k = 0; k < n_worst; ++k) render(order[order.size() - 1 - k], "worst", k);
    for (size_t k = 0; k < n_best; ++k) render(order[k], "best", k);
}

// The frames' pixel size: --mm-per-px, else the dataset's when the model records another.
void frames_pixel_size(eval::Options& opt, const api::ModelInfo& info, const sim::Dataset& d) {
    if (opt.mm_per_px) {
        if (!info.sensor)
            throw api::Error(opt.model + " has no sensor pixel size in its config; cannot rescale (--mm-per-px)");
        if (*opt.mm_per_px != info.sensor->mm_per_px) opt.frames_mm_per_px = opt.mm_per_px;
    } else if (info.sensor && d.sensor.mm_per_px != info.sensor->mm_per_px) {
        opt.frames_mm_per_px = d.sensor.mm_per_px;
    }
}

// Objects this run calls unknown that the weight file says it was trained on.
void warn_trained_unseen(const eval::Options& opt, const std::vector<eval::Job>& jobs, const std::string& index,
                         std::vector<std::string>& warnings) {
    if (auto trained = eval::trained_objects(opt.model)) {
        const std::set<std::string> names(trained->begin(), trained->end());
        for (const eval::Job& j : jobs)
            if (j.rec->object_split == "unseen" && names.count(j.rec->name))
                warnings.push_back("warning: '" + j.rec->name + "' is an unknown object (object_split unseen) of " +
                                   index + " but " + opt.model + " was trained on it (vtloc.provenance)");
    }
}

// The model's rows, then the baselines' (unless --no-baselines), and their notes.
void add_methods(Session& s, eval::Report& rep, const eval::MethodResult& result, const sim::Dataset& d,
                 const std::vector<eval::Job>& jobs) {
    std::vector<eval::MethodResult> methods{result};
    if (rep.opt.baselines) {
        methods.push_back(eval::run_chance(jobs));
        methods.push_back(eval::run_point_filtering(d, jobs));
        methods.push_back(eval::run_codebook(s, jobs, rep.opt.backend));
    }
    for (const eval::MethodResult& m : methods) {
        for (eval::Row& r : eval::make_rows(m, jobs)) rep.rows.push_back(r);
        if (m.skipped) rep.notes.push_back(m.method + " " + m.note);
        else if (m.method == "Point Filtering") rep.notes.push_back("Point Filtering: " + m.note + " (docs/usage.md)");
        else if (m.method == "Codebook") rep.notes.push_back("Codebook: " + m.note + " (docs/render_compare.md)");
    }
}

void print_run_lines(const Session& s, const eval::Options& opt, const eval::Report& rep, size_t objects,
                     const api::ModelInfo& info) {
    std::printf("data      %s: %zu objects, %d %s touches%s\n", opt.data.c_str(), objects, rep.touches_run,
                opt.split.c_str(), opt.objects == "all" ? "" : (" (" + opt.objects + " objects)").c_str());
    std::printf("device    %s\n", s.context ? s.context->device().name.c_str() : "CPU reference (--backend cpu)");
    if (opt.frames_mm_per_px)
        std::printf("rescale   frames of %g mm per pixel (%s) to the model's %g before the crop\n",
                    *opt.frames_mm_per_px, opt.mm_per_px ? "--mm-per-px" : "the dataset's sensor",
                    info.sensor->mm_per_px);
}

}  // namespace

namespace eval {
const std::vector<EvalOption> kEvalOptions{
    {"--model", true, OptionFor::both},           {"--data", true, OptionFor::both},
    {"--objects", true, OptionFor::both},         {"--json", true, OptionFor::both},
    {"--markdown", true, OptionFor::both},        {"--per-touch", true, OptionFor::both},
    {"--replot", true, OptionFor::both},  // answered before either report runs
    {"--split", true, OptionFor::single},         {"--iters", true, OptionFor::single},
    {"--topk", true, OptionFor::single},          {"--render", true, OptionFor::single},
    {"--render-count", true, OptionFor::single},  {"--skip-bad", false, OptionFor::single},
    {"--no-baselines", false, OptionFor::single}, {"--backend", true, OptionFor::single},
    {"--mm-per-px", true, OptionFor::single},     {"--cloud", true, OptionFor::single},
    {"--sequence", true, OptionFor::sequence},    {"--geometry-only", false, OptionFor::sequence},
    {"--odometry-noise", true, OptionFor::sequence}, {"--filter", true, OptionFor::sequence},
    {"--end-split", true, OptionFor::sequence},   {"--plot", true, OptionFor::sequence},
    {"--render-compare", false, OptionFor::sequence}, {"--rows", true, OptionFor::sequence}};

void refuse_other_report(const Args& a, OptionFor report) {
    for (const EvalOption& o : kEvalOptions) {
        if (o.report == OptionFor::both || o.report == report || !a.get(o.name)) continue;
        if (report == OptionFor::single) throw UsageError(std::string(o.name) + " is for --sequence");
        throw UsageError(std::string(o.name) + " is not for --sequence: it belongs to the single-touch report");
    }
}

std::string image_path(const sim::ObjectRecord& o, const sim::TouchRecord& t) {
    return (fs::path(o.folder) / t.image).string();
}
}  // namespace eval

int cmd_eval(Session& s, int argc, char** argv) {
    std::vector<OptionSpec> specs;
    for (const eval::EvalOption& o : eval::kEvalOptions) specs.push_back({o.name, o.value});
    Args a(argc, argv, 2, specs);
    if (a.help()) {
        std::fputs(kHelp, stdout);
        return 0;
    }
    if (auto r = a.get("--replot")) {  // a saved report's plot, redrawn
        std::ifstream in(*r);
        if (!in) throw api::Error(*r + ": cannot open");
        const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
        if (j.is_discarded() || !j.is_object() || j.value("format", "") != "vtloc-eval-sequence/1" || !j.contains("rows") ||
            !j["rows"].is_array())
            throw api::Error(*r + ": not a vtloc-eval-sequence/1 report");
        const std::string plot = a.required("--plot");
        try {  // a row without its keys, or of other types: the report's fault, not an internal error
            eval::plot_sequence(plot, j["rows"], j.contains("data") && j["data"].is_string() ? j["data"].get<std::string>() : "");
        } catch (const nlohmann::json::exception& e) {
            const std::string what = e.what();
            throw api::Error(*r + ": a row of this vtloc-eval-sequence/1 report is incomplete (" + what.substr(what.find(']') + 2) + ")");
        }
        return 0;
    }
    if (a.get("--sequence")) return eval::run_sequence(s, a);
    eval::refuse_other_report(a, eval::OptionFor::single);
    eval::Options opt = parse(a);
    if (opt.model.empty()) opt.model = default_model_path();

    const sim::Dataset d = sim_call([&] { return sim::read_dataset(opt.data); });
    const api::ModelInfo info = api::inspect_model(opt.model);
    const std::string index = (fs::path(d.root) / "dataset.json").string();
    if (info.sample_points != d.n_points)
        throw api::Error(opt.model + ": the model takes " + std::to_string(info.sample_points) +
                         " points per object (point.n_points), " + index + " has n_points " + std::to_string(d.n_points));

    frames_pixel_size(opt, info, d);

    eval::Report rep;
    rep.opt = opt;
    rep.config = info.name;
    rep.head = info.head;
    rep.iters = opt.iters >= 0 ? opt.iters : info.default_iters;
    std::vector<eval::Job> jobs = select(d, opt, info, rep.skips);
    size_t selected = rep.skips.size();
    for (const eval::Job& j : jobs) selected += j.touches.size();

    std::vector<std::string>& warnings = rep.warnings;
    warn_trained_unseen(opt, jobs, index, warnings);

    const bool random = is_shipped_random_model(opt.model);
    print_model(info, random);
    for (const std::string& w : warnings) std::printf("%s\n", w.c_str());
    std::fflush(stdout);

    api::Model model = load_model(s, opt.model, opt.backend);
    double engine_ms = 0;
    eval::MethodResult result = eval::run_model(model, jobs, opt, rep.skips, engine_ms);
    if (result.rows.empty()) throw api::Error(opt.data + ": no touch left to evaluate");
    rep.touches_run = int(result.rows.size());
    rep.time_per_touch_ms = engine_ms / double(result.rows.size());

    add_methods(s, rep, result, d, jobs);

    print_run_lines(s, opt, rep, jobs.size(), info);
    if (!rep.skips.empty()) rep.notes.insert(rep.notes.begin(), skip_summary(rep.skips, selected));
    std::printf("\n");
    eval::print_table(rep);

    std::vector<std::string> written;
    if (opt.json) eval::write_json(*opt.json, rep, result, jobs), written.push_back(*opt.json);
    if (opt.markdown) eval::write_markdown(*opt.markdown, rep), written.push_back(*opt.markdown);
    if (opt.per_touch) eval::write_per_touch_csv(*opt.per_touch, result, jobs), written.push_back(*opt.per_touch);
    if (opt.render_dir) render_extremes(opt, result, jobs, info.name, written);
    for (const std::string& w : written) std::printf("wrote     %s\n", w.c_str());
    return 0;
}

}  // namespace vtloc::cli
