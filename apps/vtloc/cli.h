#pragma once
// Shared pieces of the vtloc command-line tool: argument parsing, the lazily
// made Vulkan context, shipped-file lookup, and the commands themselves. The
// tool uses the public API (<vtloc/vtloc.h>) only.
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/shipped.h"
#include "vtloc/vtloc.h"

namespace vtloc::cli {

// A command-line mistake: exit code 2 with the command's name and a hint.
class UsageError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

struct OptionSpec {
    std::string name;       // "--model"
    bool value = true;      // takes a value
    bool repeat = false;    // may be given more than once
};

class Args {
public:
    // Parses argv[first..]; `--help`/`-h` anywhere sets help(). Throws
    // UsageError for unknown options, missing values, repeats, and more
    // positional arguments than max_positional.
    Args(int argc, char** argv, int first, std::vector<OptionSpec> specs, size_t max_positional = 0);

    bool help() const { return help_; }
    bool flag(const std::string& name) const;
    std::optional<std::string> get(const std::string& name) const;
    std::vector<std::string> all(const std::string& name) const;
    std::string required(const std::string& name) const;
    int integer(const std::string& name, int fallback, int lo, int hi) const;
    double number(const std::string& name, double fallback) const;
    const std::vector<std::string>& positional() const { return positional_; }

private:
    bool help_ = false;
    std::vector<std::pair<std::string, std::string>> given_;
    std::vector<std::string> positional_;
};

// "1.5,2,3" -> numbers; throws UsageError naming `what` unless there are `count`.
std::vector<double> parse_numbers(const std::string& text, size_t count, const std::string& what);

// The Vulkan context, made on first use (CPU-backend runs never make one), so
// that main can report validation messages whatever the command did.
struct Session {
    std::optional<api::Context> context;
    api::Context& gpu() {
        if (!context) context.emplace();
        return *context;
    }
};

// Shipped files (models/, examples/): the first folder of base/shipped.h's
// search ($VTLOC_DATA_DIR, an install's share/vtloc, build/.., the source tree)
// that holds the default model. Throws api::Error when none does.
std::filesystem::path shipped_dir();
// kDefaultModel, kRandomModel: base/shipped.h
// The demo's example (examples/<name>.json): a tour of 8 touches whose last is a test touch
// of the synthetic benchmark (multi-touch filter; --example picks a single touch).
inline constexpr const char* kDefaultExample = "potato_tour";
bool is_shipped_random_model(const std::string& path);
std::string default_model_path();

// Options every touch command shares: --topk --iters --symmetry-axis
// --symmetry-order --no-gma --backend --mm-per-px.
std::vector<OptionSpec> touch_option_specs();
api::LocalizeOptions touch_options(const Args& a);
// A pixel size option (--mm-per-px): unset, or a finite number > 0 (else UsageError).
std::optional<double> mm_per_px_option(const Args& a, const std::string& name = "--mm-per-px");
extern const char* kTouchOptionsHelp;

// The object of a touch command: --object FILE, or --depth D.png --intrinsics
// fx,fy,cx,cy [--mask M.png] [--depth-unit MM] (apps/vtloc/object_source.cpp).
std::vector<OptionSpec> object_option_specs();
extern const char* kObjectOptionsHelp;
api::Object encode_cli_object(api::Model& model, const Args& a, const std::string& candidates, api::Backend backend);
std::string object_label(const Args& a);  // the file named, for messages and captions

// Model on the requested backend (no Vulkan for --backend cpu).
api::Model load_model(Session& s, const std::string& path, api::Backend backend);

// Creates a folder (and its parents); throws api::Error naming it when it cannot.
void make_folder(const std::string& path);

// The gel shape of a frame read from `frame_path` (the empty frame from `empty_path`, or the
// calibration's with none): the reader's refusal of either begins with that frame's file, and
// every refusal ends with `where` (e.g. " (touch 2 of tour.json)").
api::GelShape read_gel_shape(api::GelShapeReader& reader, const std::string& frame_path, const api::TactileImage& frame,
                             const api::TactileImage* empty, const std::string& empty_path, const std::string& where = "");
// The same refusals without reading the shape (no GPU work).
void check_gel_frame(const api::GelShapeReader& reader, const std::string& frame_path, const api::TactileImage& frame,
                     const api::TactileImage* empty, const std::string& empty_path, const std::string& where = "");

// Formats a point "(x, y, z)" with `digits` decimals.
std::string point_str(const std::array<double, 3>& p, int digits = 2);

int cmd_demo(Session& s, int argc, char** argv);
int cmd_localize(Session& s, int argc, char** argv);
int localize_codebook(Session& s, int argc, char** argv);  // vtloc localize --method codebook
int cmd_sequence(Session& s, int argc, char** argv);
int cmd_shape(Session& s, int argc, char** argv);
int cmd_calibrate(Session& s, int argc, char** argv);
int cmd_info(Session& s, int argc, char** argv);
int cmd_devices(Session& s, int argc, char** argv);
int cmd_synth(Session& s, int argc, char** argv);
int cmd_eval(Session& s, int argc, char** argv);
int cmd_check(Session& s, int argc, char** argv);

}  // namespace vtloc::cli
