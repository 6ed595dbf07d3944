// vtloc sequence: several touches with known motions -> a belief over the candidates.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <numeric>

#include "apps/vtloc/report.h"

namespace vtloc::cli {

namespace {

const char* kHelp =
    "usage: vtloc sequence [--model M] (--object FILE | --depth D.png --intrinsics K)\n"
    "                      (--touch IMG[,dx,dy,dz] ... | --touches FILE.json) [options]\n"
    "\n"
    "Multi-contact localisation (SPEC section 6): touches on one object, in order, with the\n"
    "sensor's motion between them, give a belief over the candidate contact points.\n"
    "\n"
    "  --model M                 weight file (default: the shipped models/vtloc-lite)\n"
    "%s"
    "  --touch IMG[,dx,dy,dz]    one touch (repeat, in order); dx,dy,dz = the sensor's\n"
    "                            displacement since the previous touch, object units\n"
    "                            (default 0,0,0; none for the first touch)\n"
    "  --touches FILE.json       the touches as {\"touches\": [{\"tactile\": \"a.png\"},\n"
    "                            {\"tactile\": \"b.png\", \"motion\": [dx, dy, dz]}, ...]}\n"
    "                            (paths relative to the JSON file)\n"
    "  --candidates F            candidate contact points (default: the object's points)\n"
    "  --sigma S                 likelihood width, normalised frame (default 0.2)\n"
    "  --sigma-m S               motion noise, normalised frame (default 0.05)\n"
    "  --window W                touches used: the current one and W-1 before it (default 4, 0 = all)\n"
    "%s"
    "  --json                    print the result as JSON\n"
    "  --heatmap OUT.ply         write the belief's heat-map as a PLY (contact_prob + colour)\n"
    "  --render OUT.png          write a picture of the belief's heat-map\n"
    "\n"
    "All tactile images must have one size. Exit status: 0 ok, 1 bad input or runtime\n"
    "error, 2 usage error.\n";

struct Touch {
    std::string image;
    std::optional<std::array<double, 3>> motion;
};

Touch parse_touch(const std::string& arg) {
    // IMG,dx,dy,dz: the last three comma-separated fields, when there are
    // three more after the path (paths with commas still work without a motion).
    size_t c3 = arg.rfind(','), c2 = c3 == std::string::npos || c3 == 0 ? std::string::npos : arg.rfind(',', c3 - 1);
    size_t c1 = c2 == std::string::npos || c2 == 0 ? std::string::npos : arg.rfind(',', c2 - 1);
    if (c1 == std::string::npos) return {arg, std::nullopt};
    std::vector<double> v = parse_numbers(arg.substr(c1 + 1), 3, "--touch " + arg);
    return {arg.substr(0, c1), std::array<double, 3>{v[0], v[1], v[2]}};
}

std::vector<Touch> read_touch_file(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw api::Error(path + ": cannot open");
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception&) {
        throw api::Error(path + ": not valid JSON");
    }
    if (!j.is_object() || !j.contains("touches") || !j["touches"].is_array())
        throw api::Error(path + ": expected {\"touches\": [...]}");
    const std::filesystem::path base = std::filesystem::path(path).parent_path();
    std::vector<Touch> out;
    for (size_t i = 0; i < j["touches"].size(); ++i) {
        const nlohmann::json& t = j["touches"][i];
        const std::string where = path + ": touch " + std::to_string(i + 1);
        if (!t.is_object() || !t.contains("tactile") || !t["tactile"].is_string())
            throw api::Error(where + " needs a \"tactile\" image path");
        Touch touch{(base / t["tactile"].get<std::string>()).lexically_normal().string(), std::nullopt};
        if (t.contains("motion")) {
            const nlohmann::json& m = t["motion"];
            if (!m.is_array() || m.size() != 3 || !m[0].is_number() || !m[1].is_number() || !m[2].is_number())
                throw api::Error(where + ": \"motion\" must be [dx, dy, dz]");
            touch.motion = std::array<double, 3>{m[0].get<double>(), m[1].get<double>(), m[2].get<double>()};
        }
        out.push_back(touch);
    }
    return out;
}

// --touches FILE.json or the --touch options, in order.
std::vector<Touch> gather_touches(const Args& a) {
    std::vector<Touch> touches;
    if (a.get("--touches") && a.flag("--touch")) throw UsageError("give --touch or --touches, not both");
    if (auto file = a.get("--touches")) touches = read_touch_file(*file);
    for (const std::string& t : a.all("--touch")) touches.push_back(parse_touch(t));
    if (touches.empty()) throw UsageError("no touches: give --touch IMG[,dx,dy,dz] or --touches FILE.json");
    if (touches[0].motion) throw api::Error("the first touch has no previous one to move from; drop its motion");
    return touches;
}

// What the outputs and the report need of one sequence run.
struct Run {
    const std::vector<Touch>& touches;
    const std::vector<std::array<double, 3>>& motions;
    const api::ModelInfo& info;
    const api::Object& object;
    const api::SequenceResult& r;
    const std::string &object_path, &candidates;
    bool random;
    std::vector<size_t> order;  // the most believed candidates, best first (argmax included)
    size_t shown;               // how many of them the report shows

    std::array<double, 3> candidate(size_t i) const {
        const std::vector<float>& c = object.candidates();
        return std::array<double, 3>{c[i * 3], c[i * 3 + 1], c[i * 3 + 2]};
    }
};

void rank_candidates(Run& run) {
    const std::vector<float>& belief = run.r.belief;
    run.order.resize(belief.size());
    std::iota(run.order.begin(), run.order.end(), size_t(0));
    run.shown = std::min<size_t>(5, run.order.size());
    std::partial_sort(run.order.begin(), run.order.begin() + long(run.shown), run.order.end(),
                      [&](size_t x, size_t y) { return belief[x] > belief[y] || (belief[x] == belief[y] && x < y); });
}

nlohmann::json write_outputs(const Args& a, const Run& run) {
    nlohmann::json outputs = nlohmann::json::object();
    write_heatmap_option(a, run.object, run.r.heatmap, outputs);
    if (auto p = a.get("--render")) {
        api::RenderOptions ro;
        ro.contact = run.r.best_point;
        ro.caption = run.info.name + (run.random ? " (RANDOM weights)" : "") + ": belief after " +
                     std::to_string(run.touches.size()) + " touches on " + run.object_path;
        api::render_heatmap_png(*p, run.object, run.r.heatmap, ro);
        outputs["render"] = *p;
    }
    return outputs;
}

void print_json(const Session& s, const Run& run, const nlohmann::json& outputs) {
    const api::SequenceResult& r = run.r;
    nlohmann::json jt = nlohmann::json::array();
    for (size_t i = 0; i < run.touches.size(); ++i) {
        nlohmann::json t = touch_json(r.touches[i]);
        t["tactile"] = run.touches[i].image;
        t["motion"] = i == 0 ? nlohmann::json(nullptr) : point_json(run.motions[i - 1]);
        jt.push_back(t);
    }
    nlohmann::json top = nlohmann::json::array();
    for (size_t k = 0; k < run.shown; ++k)
        top.push_back({{"index", run.order[k]}, {"belief", r.belief[run.order[k]]},
                       {"point", point_json(run.candidate(run.order[k]))}});
    nlohmann::json j{{"model", model_json(run.info, run.random)},
                     {"object", object_json(run.object, run.candidates)},
                     {"touches", jt},
                     {"belief", {{"best", r.best}, {"best_point", point_json(r.best_point)}, {"top", top},
                                 {"values", r.belief}}},
                     {"timings_ms", timings_json(r.timings)},
                     {"outputs", outputs}};
    if (s.context) j["device"] = s.context->device().name;
    std::printf("%s\n", j.dump(2).c_str());
}

void print_text(const Run& run, const nlohmann::json& outputs) {
    const api::SequenceResult& r = run.r;
    print_model(run.info, run.random);
    std::printf("object    %s: %zu points, %zu candidates%s\n", run.object_path.c_str(), run.object.cloud().size(),
                run.object.candidate_count(),
                run.candidates.empty() ? " (its points)" : (" from " + run.candidates).c_str());
    for (size_t i = 0; i < run.touches.size(); ++i) {
        std::printf("touch %zu   %s", i + 1, run.touches[i].image.c_str());
        if (i > 0) std::printf(", moved %s", point_str(run.motions[i - 1]).c_str());
        std::printf("\n          contact %s\n", point_str(r.touches[i].contact).c_str());
    }
    std::printf("belief    argmax: candidate %d at %s (belief %.3g)\n", r.best, point_str(r.best_point).c_str(),
                double(r.belief[size_t(r.best)]));
    for (size_t k = 1; k < run.shown; ++k)
        std::printf("          then candidate %zu at %s (%.3g)\n", run.order[k],
                    point_str(run.candidate(run.order[k])).c_str(), double(r.belief[run.order[k]]));
    std::printf("time      %.1f ms for the %zu touches and the belief\n", r.timings.wall_ms, run.touches.size());
    for (auto& [what, path] : outputs.items()) std::printf("wrote     %s\n", path.get<std::string>().c_str());
}

}  // namespace

int cmd_sequence(Session& s, int argc, char** argv) {
    std::vector<OptionSpec> specs{{"--model"},   {"--touch", true, true}, {"--touches"},
                                  {"--candidates"}, {"--sigma"}, {"--sigma-m"},         {"--window"},
                                  {"--json", false}, {"--heatmap"}, {"--render"}};
    for (OptionSpec& o : touch_option_specs()) specs.push_back(o);
    for (OptionSpec& o : object_option_specs()) specs.push_back(o);
    Args a(argc, argv, 2, specs);
    if (a.help()) {
        std::printf(kHelp, kObjectOptionsHelp, kTouchOptionsHelp);
        return 0;
    }
    const std::string object_path = object_label(a);
    if (object_path.empty()) throw UsageError("give --object FILE or --depth D.png --intrinsics fx,fy,cx,cy");
    const std::string candidates = a.get("--candidates").value_or("");
    const std::vector<Touch> touches = gather_touches(a);
    api::LocalizeOptions opt = touch_options(a);
    api::BeliefOptions belief;
    belief.sigma = a.number("--sigma", belief.sigma);
    belief.sigma_m = a.number("--sigma-m", belief.sigma_m);
    belief.window = a.integer("--window", belief.window, 0, 1 << 20);

    std::vector<api::TactileImage> images;
    std::vector<std::array<double, 3>> motions;
    for (size_t i = 0; i < touches.size(); ++i) {
        images.push_back(api::load_tactile_image(touches[i].image));
        if (i > 0) motions.push_back(touches[i].motion.value_or(std::array<double, 3>{0, 0, 0}));
    }
    const auto model_arg = a.get("--model");
    const std::string model_file = model_arg ? *model_arg : default_model_path();
    api::Model model = load_model(s, model_file, opt.backend);
    api::Object object = encode_cli_object(model, a, candidates, opt.backend);
    api::SequenceResult r = model.localize_sequence(object, images, motions, opt, belief);

    Run run{touches, motions, model.info(), object, r, object_path, candidates, is_shipped_random_model(model_file), {}, 0};
    rank_candidates(run);
    const nlohmann::json outputs = write_outputs(a, run);
    if (a.flag("--json")) print_json(s, run, outputs);
    else print_text(run, outputs);
    return 0;
}

}  // namespace vtloc::cli
