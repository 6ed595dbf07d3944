// vtloc demo: the shipped model on a shipped example, from any working directory.
#include <cmath>
#include <cstdio>
#include <fstream>

#include "apps/vtloc/report.h"

namespace vtloc::cli {

namespace fs = std::filesystem;

namespace {

const char* kHelp =
    "usage: vtloc demo [--example NAME] [--out DIR] [--model M] [--geometry-only] [--mm-per-px MM]\n"
    "\n"
    "By default, the engine's job: several touches on a shipped object and the robot's motions\n"
    "between them (examples/potato_tour.json: 8 simulated touches along a tour of a potato, the\n"
    "last one a test touch of the synthetic benchmark) go through the multi-touch filter with the\n"
    "shipped model's heat-map of each touch (SPEC section 6). It prints the error of the contact\n"
    "estimate after each touch and writes the belief after each touch side by side (belief.png).\n"
    "\n"
    "--example picks a single touch instead: the shipped model (models/vtloc-lite-everyday.safetensors,\n"
    "trained on the synthetic benchmark; docs/results.md) on one touch it never trained on\n"
    "(plate_test0, a dinner plate) or one of the mug touches (real GelSight frames, not taken on the mug),\n"
    "printing the predicted and the true contact and writing a heat-map picture (PNG) and cloud\n"
    "(PLY).\n"
    "\n"
    "  --example E   1..3 (examples/touch_0E.json) or a name (examples/E.json: a touch, or\n"
    "                a touches file with true contacts; default: potato_tour)\n"
    "  --out DIR     where to write the pictures (default: <temp dir>/vtloc-demo)\n"
    "  --model M     another weight file, e.g. your trained export\n"
    "  --geometry-only  a sequence without the network term (no model is loaded)\n"
    "  --mm-per-px MM  the frame's pixel size in mm: rescale it to the model's sensor\n"
    "                pixel size before the crop (the model must record a sensor)\n";

struct Example {
    fs::path object, tactile, candidates;  // candidates: empty = the cloud's own points
    std::array<double, 3> contact{};
    std::string where;
    double diameter_mm = 0;  // the object's size, when the example records it (ND = error / size)
};

Example read_example(const fs::path& json_path) {
    std::ifstream in(json_path);
    if (!in) throw api::Error(json_path.string() + ": cannot open");
    try {
        nlohmann::json j = nlohmann::json::parse(in);
        Example e;
        e.object = json_path.parent_path() / j.at("object").get<std::string>();
        e.tactile = json_path.parent_path() / j.at("tactile").get<std::string>();
        if (j.contains("candidates")) e.candidates = json_path.parent_path() / j.at("candidates").get<std::string>();
        for (size_t i = 0; i < 3; ++i) e.contact[i] = j.at("contact").at(i).get<double>();
        e.where = j.value("where", "");
        e.diameter_mm = j.value("object_diameter_mm", 0.0);
        return e;
    } catch (const nlohmann::json::exception& x) {
        throw api::Error(json_path.string() + ": not a VTLoc example (" + std::string(x.what()) + ")");
    }
}

// A touches file ("format": "vtloc-touches/2") rather than a single-touch example.
bool is_sequence_file(const fs::path& p) {
    std::ifstream in(p);
    const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    return j.is_object() && j.contains("format") && j["format"] == "vtloc-touches/2";
}

double distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

}  // namespace

int demo_sequence(Session& s, const fs::path& json_path, const fs::path& model_path, bool geometry_only,
                  const api::LocalizeOptions& opt, const fs::path& out);

int cmd_demo(Session& s, int argc, char** argv) {
    Args a(argc, argv, 2, {{"--example"}, {"--out"}, {"--model"}, {"--mm-per-px"}, {"--geometry-only", false}});
    if (a.help()) {
        std::fputs(kHelp, stdout);
        return 0;
    }
    // A number picks one of the mug touches, a name any examples/<name>.json.
    std::string name = a.get("--example").value_or(kDefaultExample);
    if (name.size() == 1 && name[0] >= '1' && name[0] <= '3') name = "touch_0" + name;
    else if (name.empty() || name.find_first_of("/\\.") != std::string::npos)
        throw UsageError("--example takes 1..3 or the name of an examples/*.json file");
    api::LocalizeOptions opt;
    opt.mm_per_px = mm_per_px_option(a);
    const fs::path out = a.get("--out") ? fs::path(*a.get("--out")) : fs::temp_directory_path() / "vtloc-demo";
    const fs::path root = shipped_dir();
    const fs::path model_path = a.get("--model") ? fs::path(*a.get("--model")) : root / kDefaultModel;
    const bool random = is_shipped_random_model(model_path.string());
    const fs::path json_path = root / "examples" / (name + ".json");
    if (!fs::exists(json_path)) throw api::Error(json_path.string() + ": no such example");
    if (is_sequence_file(json_path)) return demo_sequence(s, json_path, model_path, a.flag("--geometry-only"), opt, out);
    if (a.flag("--geometry-only")) throw UsageError("--geometry-only is for a sequence; " + name + " is a single touch");
    Example ex = read_example(json_path);

    api::Model model(s.gpu(), model_path.string());
    print_model(model.info(), random);
    std::printf("device    %s\n", s.gpu().device().name.c_str());
    api::TactileImage image = api::load_tactile_image(ex.tactile.string());
    api::Object object = model.encode_object(ex.object.string(), ex.candidates.string());
    std::printf("object    %s: %zu points, %zu candidate contacts\n", ex.object.string().c_str(),
                object.cloud().size(), object.candidate_count());
    std::printf("touch     %s (%dx%d GelSight frame)\n", ex.tactile.string().c_str(), image.width, image.height);
    api::TouchResult r = model.localize(object, image, opt);

    std::printf("predicted %s mm\n", point_str(r.contact, 1).c_str());
    std::printf("true      %s mm (%s)\n", point_str(ex.contact, 1).c_str(), ex.where.c_str());
    const double err = distance(r.contact, ex.contact);
    std::printf("error     %.1f mm", err);
    if (ex.diameter_mm > 0) std::printf(" = %.1f %% of the object's %.0f mm (ND)", 100 * err / ex.diameter_mm, ex.diameter_mm);
    std::printf("%s\n", random ? " (untrained weights: expect nothing better than chance)" : "");
    if (r.alignment) std::printf("alignment %.4g (GMA chamfer; lower = better)\n", double(*r.alignment));

    make_folder(out.string());
    const std::string png = (out / "heatmap.png").string(), ply = (out / "heatmap.ply").string();
    api::RenderOptions ro;
    ro.contact = r.contact;
    ro.ground_truth = ex.contact;
    ro.tactile = &image;
    ro.caption = model.info().name + (random ? " with RANDOM weights" : "") + ": " +
                 ex.tactile.filename().string() + " on " + ex.object.filename().string();
    api::render_heatmap_png(png, object, r.heatmap, ro);
    api::write_heatmap_ply(ply, object, r.heatmap);
    std::printf("time      %.0f ms for the touch (a first run includes shader compilation)\n", r.timings.wall_ms);
    std::printf("wrote     %s\n          %s\n", png.c_str(), ply.c_str());
    return 0;
}

}  // namespace vtloc::cli
