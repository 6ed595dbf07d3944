#pragma once
// `vtloc eval` (docs/eval.md): the pieces shared by its source files.
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "apps/vtloc/cli.h"
#include "engine/sim/dataset.h"
#include "engine/sim/metrics.h"

namespace vtloc::cli::eval {

// Every option of `vtloc eval` and the report it belongs to (cmd_eval.cpp): one table, so an
// option given to the other report is refused by name, and a new one is placed once.
enum class OptionFor { both, single, sequence };
struct EvalOption {
    const char* name;
    bool value;  // takes a value
    OptionFor report;
};
extern const std::vector<EvalOption> kEvalOptions;
// Throws UsageError naming the first option given that belongs to the other report.
void refuse_other_report(const Args& a, OptionFor report);

// vtloc eval --sequence (eval_sequence.cpp): SPEC 6's protocols; prints and writes its own report.
int run_sequence(Session& s, const Args& a);
// ND and ND up to symmetry against T (the "all" rows of a vtloc-eval-sequence/1 report) as a PNG.
void plot_sequence(const std::string& path, const nlohmann::json& rows, const std::string& data);

struct Options {
    std::string model, data;
    std::string split = "test";    // test | train | all
    std::string objects = "all";   // all | known | unknown
    int iters = -1;                // -1 = the model's default
    int topk = 5;
    std::string cloud = "full";    // full (points.csv) | xyz (its points, normals estimated) | view (view.xyz)
    std::optional<std::string> json, markdown, per_touch, render_dir;
    int render_count = 3;
    bool skip_bad = false, baselines = true;
    api::Backend backend = api::Backend::Gpu;
    std::optional<double> mm_per_px;         // --mm-per-px: the frames' pixel size
    std::optional<double> frames_mm_per_px;  // what the frames are rescaled from (unset: no rescale)
};

// A touch that was left out (--skip-bad), and why.
struct Skip {
    std::string object;
    int touch = -1;
    std::string file, reason;
};

// One object to evaluate: its record, metric geometry and selected touches.
struct Job {
    const sim::ObjectRecord* rec = nullptr;
    sim::MetricObject geom;
    std::vector<const sim::TouchRecord*> touches;  // selected, in id order
    int topk = 5;                                  // --topk capped at the candidate count
};

// One evaluated touch of one method.
struct TouchRow {
    size_t job = 0;
    const sim::TouchRecord* touch = nullptr;
    sim::TouchMetrics m;
    sim::Point3 contact{};        // the prediction, object units
    std::vector<float> heat;      // kept for --render (model rows only)
};

// A method's results: per job, the touch scores that its rows average.
struct MethodResult {
    std::string method;   // the model's config name, "Chance", "Point Filtering", "Codebook"
    std::string label;    // in tables: "Chance (analytic)"; empty = method
    std::string note;     // "analytic", "skipped: ...", ...
    bool skipped = false;
    std::vector<std::vector<sim::TouchScore>> scores;  // [job][touch]
    std::vector<TouchRow> rows;                        // model rows only
    std::vector<api::Object> encoded;                  // [job], model only (for --render)
};

struct Row {
    std::string method, label, subset, note;
    sim::RowMetrics m;
};

struct Report {
    Options opt;
    std::string config;              // model config name
    std::string head;                // "ilu" or "mcr"
    std::vector<Skip> skips;
    int iters = 0;                   // effective ILU iterations
    std::vector<Row> rows;
    std::vector<std::string> notes;  // printed under the table
    std::vector<std::string> warnings;  // printed before it (provenance)
    double time_per_touch_ms = 0;
    int touches_run = 0;
};

// Touch image path (object folder + image column).
std::string image_path(const sim::ObjectRecord& o, const sim::TouchRecord& t);

// ---- eval_run.cpp -----------------------------------------------------------
// Runs the model on every job's touches (batches per object). Touches whose
// image cannot be read are skipped into `skips` and dropped from their job with
// --skip-bad, else throw. engine_ms = wall time of the engine calls (localize).
MethodResult run_model(api::Model& model, std::vector<Job>& jobs, const Options& opt, std::vector<Skip>& skips,
                       double& engine_ms);

// ---- eval_baselines.cpp -----------------------------------------------------
// Over the same touches as the model (the jobs after run_model).
MethodResult run_chance(const std::vector<Job>& jobs);
// Skipped (with a note) for jobs without mesh.ply; the calibration is the
// shipped one (sim::default_calibration_path()).
MethodResult run_point_filtering(const sim::Dataset& d, const std::vector<Job>& jobs);
// Render-and-compare alone (SPEC 9; the paper's fourth baseline): skipped (with a note) for
// jobs without mesh.ply or on the CPU backend.
MethodResult run_codebook(Session& s, const std::vector<Job>& jobs, api::Backend backend);

// ---- eval_report.cpp --------------------------------------------------------
// Rows for non-uniform / uniform / all (a subset without objects is left out).
std::vector<Row> make_rows(const MethodResult& r, const std::vector<Job>& jobs);
void print_table(const Report& rep);
void write_markdown(const std::string& path, const Report& rep);
void write_json(const std::string& path, const Report& rep, const MethodResult& model, const std::vector<Job>& jobs);
void write_per_touch_csv(const std::string& path, const MethodResult& model, const std::vector<Job>& jobs);

// ---- eval_progress.cpp ------------------------------------------------------
// A progress bar on stderr, drawn only when stderr is a terminal.
class Progress {
public:
    Progress(std::string label, size_t total);
    ~Progress();
    void advance(size_t n = 1);
    void finish();

private:
    void draw();
    std::string label_;
    size_t total_ = 0, done_ = 0;
    bool tty_ = false, finished_ = false;
};

// ---- eval_provenance.cpp ----------------------------------------------------
// Names of the objects the weight file says it was trained on (metadata
// `vtloc.provenance`: {"objects": [{"name", "object_split"}]} (seen ones) or
// {"train_objects": [names]}); nullopt when the file records none.
std::optional<std::vector<std::string>> trained_objects(const std::string& model_path);

}  // namespace vtloc::cli::eval
