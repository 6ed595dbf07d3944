// Argument parsing and the options the touch commands share.
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "apps/vtloc/cli.h"

namespace vtloc::cli {

Args::Args(int argc, char** argv, int first, std::vector<OptionSpec> specs, size_t max_positional) {
    auto find = [&](const std::string& name) -> const OptionSpec* {
        for (const OptionSpec& s : specs)
            if (s.name == name) return &s;
        return nullptr;
    };
    bool options_done = false;
    for (int i = first; i < argc; ++i) {
        std::string arg = argv[i];
        if (options_done || arg.size() < 2 || arg[0] != '-' || (arg[1] != '-' && arg != "-h")) {
            positional_.push_back(arg);
            continue;
        }
        if (arg == "--") {
            options_done = true;
            continue;
        }
        if (arg == "--help" || arg == "-h") {
            help_ = true;
            continue;
        }
        std::string name = arg, value;
        bool inline_value = false;
        if (size_t eq = arg.find('='); eq != std::string::npos) {
            name = arg.substr(0, eq);
            value = arg.substr(eq + 1);
            inline_value = true;
        }
        const OptionSpec* spec = find(name);
        if (!spec) throw UsageError("unknown option '" + name + "'");
        if (spec->value && !inline_value) {
            if (i + 1 >= argc) throw UsageError("option '" + name + "' needs a value");
            value = argv[++i];
        } else if (!spec->value && inline_value) {
            throw UsageError("option '" + name + "' takes no value");
        }
        if (!spec->repeat && get(name)) throw UsageError("option '" + name + "' given twice");
        given_.push_back({name, value});
    }
    if (!help_ && positional_.size() > max_positional)
        throw UsageError("unexpected argument '" + positional_[max_positional] + "'");
}

bool Args::flag(const std::string& name) const { return get(name).has_value(); }

std::optional<std::string> Args::get(const std::string& name) const {
    for (auto& [n, v] : given_)
        if (n == name) return v;
    return std::nullopt;
}

std::vector<std::string> Args::all(const std::string& name) const {
    std::vector<std::string> out;
    for (auto& [n, v] : given_)
        if (n == name) out.push_back(v);
    return out;
}

std::string Args::required(const std::string& name) const {
    auto v = get(name);
    if (!v) throw UsageError("missing " + name);
    return *v;
}

int Args::integer(const std::string& name, int fallback, int lo, int hi) const {
    auto v = get(name);
    if (!v) return fallback;
    char* end = nullptr;
    long x = std::strtol(v->c_str(), &end, 10);
    if (v->empty() || *end != '\0' || x < lo || x > hi)
        throw UsageError(name + " must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi) +
                         ", got '" + *v + "'");
    return int(x);
}

double Args::number(const std::string& name, double fallback) const {
    auto v = get(name);
    return v ? parse_numbers(*v, 1, name).at(0) : fallback;
}

std::vector<double> parse_numbers(const std::string& text, size_t count, const std::string& what) {
    std::vector<double> out;
    size_t start = 0;
    while (true) {
        size_t comma = text.find(',', start);
        std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        char* end = nullptr;
        double x = std::strtod(item.c_str(), &end);
        if (item.empty() || *end != '\0' || !std::isfinite(x))
            throw UsageError(what + ": '" + item + "' is not a finite number");
        out.push_back(x);
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    if (out.size() != count)
        throw UsageError(what + " needs " + std::to_string(count) + " comma-separated numbers, got " +
                         std::to_string(out.size()));
    return out;
}

const char* kTouchOptionsHelp =
    "  --topk K                  top-K candidates to keep (default: the model's K)\n"
    "  --iters N                 ILU iterations, 0..64 (default: the model's)\n"
    "  --symmetry-axis px,py,pz,dx,dy,dz\n"
    "                            axis of a rotational symmetry (point and direction, object units)\n"
    "  --symmetry-order M        M-fold symmetry prior on the heat-map (needs --symmetry-axis)\n"
    "  --no-gma                  skip GMA (no alignment score; faster)\n"
    "  --backend gpu|cpu         Vulkan (default) or the plain C++ reference ops\n"
    "  --mm-per-px MM            the frames' pixel size in mm: rescale them to the model's sensor\n"
    "                            pixel size before the crop (the model must record a sensor)\n";

std::vector<OptionSpec> touch_option_specs() {
    return {{"--topk"}, {"--iters"},   {"--symmetry-axis"}, {"--symmetry-order"}, {"--no-gma", false},
            {"--backend"}, {"--mm-per-px"}};
}

api::LocalizeOptions touch_options(const Args& a) {
    api::LocalizeOptions o;
    o.top_k = a.integer("--topk", 0, 1, api::kMaxTopK);
    o.iters = a.integer("--iters", -1, 0, api::kMaxIterations);
    o.gma = !a.flag("--no-gma");
    std::string backend = a.get("--backend").value_or("gpu");
    if (backend != "gpu" && backend != "cpu") throw UsageError("--backend must be gpu or cpu, got '" + backend + "'");
    o.backend = backend == "gpu" ? api::Backend::Gpu : api::Backend::Cpu;
    auto axis = a.get("--symmetry-axis");
    if (axis.has_value() != a.flag("--symmetry-order"))
        throw UsageError("--symmetry-axis and --symmetry-order go together");
    if (axis) {
        std::vector<double> v = parse_numbers(*axis, 6, "--symmetry-axis");
        if (v[3] == 0 && v[4] == 0 && v[5] == 0) throw UsageError("--symmetry-axis: the direction is zero");
        o.symmetry = api::Symmetry{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}, a.integer("--symmetry-order", 1, 1, 360)};
    }
    o.mm_per_px = mm_per_px_option(a);
    return o;
}

std::optional<double> mm_per_px_option(const Args& a, const std::string& name) {
    auto v = a.get(name);
    if (!v) return std::nullopt;
    char* end = nullptr;
    double x = std::strtod(v->c_str(), &end);
    if (v->empty() || *end != '\0' || !std::isfinite(x) || !(x > 0))
        throw UsageError(name + " must be a finite number > 0 (mm per pixel), got '" + *v + "'");
    return x;
}

api::Model load_model(Session& s, const std::string& path, api::Backend backend) {
    return backend == api::Backend::Cpu ? api::Model(path) : api::Model(s.gpu(), path);
}

void make_folder(const std::string& path) {
    std::error_code ec;
    std::filesystem::create_directories(path, ec);
    if (ec) throw api::Error(path + ": cannot create the folder (" + ec.message() + ")");
}

namespace {

// f's result; its refusal ends with `where`.
template <class F>
auto with_where(const std::string& where, F&& f) -> decltype(f()) {
    try {
        return f();
    } catch (const api::Error& e) {
        if (where.empty()) throw;
        throw api::Error(e.what() + where);
    }
}

}  // namespace

api::GelShape read_gel_shape(api::GelShapeReader& reader, const std::string& frame_path, const api::TactileImage& frame,
                             const api::TactileImage* empty, const std::string& empty_path, const std::string& where) {
    return with_where(where, [&] {
        return reader.read(frame, empty, frame_path.empty() ? "frame" : frame_path, empty_path.empty() ? "empty frame" : empty_path);
    });
}

void check_gel_frame(const api::GelShapeReader& reader, const std::string& frame_path, const api::TactileImage& frame,
                     const api::TactileImage* empty, const std::string& empty_path, const std::string& where) {
    with_where(where, [&] {
        reader.check_frame(frame, empty, frame_path.empty() ? "frame" : frame_path, empty_path.empty() ? "empty frame" : empty_path);
    });
}

std::string point_str(const std::array<double, 3>& p, int digits) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "(%.*f, %.*f, %.*f)", digits, p[0], digits, p[1], digits, p[2]);
    return buf;
}

}  // namespace vtloc::cli
