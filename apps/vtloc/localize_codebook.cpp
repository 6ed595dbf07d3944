// vtloc localize --method codebook: one touch by render-and-compare alone (SPEC 9; the
// paper's fourth baseline, MidasTouch's codebook without its learnt encoder). The gel's
// shape read from the frame is scored against what every pose on the object's surface
// would press; the belief over those poses, summed over spins, is the heat-map, its
// modes the top-K. No network.
#include <chrono>
#include <cstdio>

#include "apps/vtloc/report.h"

namespace vtloc::cli {

namespace {

const char* kHelp =
    "usage: vtloc localize --method codebook --tactile IMG --object MESH [options]\n"
    "\n"
    "Localises one touch by render-and-compare alone (SPEC 9): the gel's shape from the\n"
    "frame against the height each pose on the object's surface would press. No network.\n"
    "\n"
    "  --tactile IMG             the frame (the calibration's size, or larger with its aspect)\n"
    "  --object MESH             the object: a mesh, or a dense point cloud with normals (about a\n"
    "                            point per mm^2 or more; a sparse one is refused)\n"
    "  --background EMPTY.png    the sensor's frame with nothing pressed (default: the calibration's)\n"
    "  --calibration C           a Taxim-style calibration (default: the shipped GelSight one)\n"
    "  --codebook FILE           cache the object's codebook here (read when it is this object's)\n"
    "  --object-units K          multiply the object's coordinates by K (glTF in metres: 1000)\n"
    "  --topk K                  modes to print (default 5)\n"
    "  --render OUT.png          the belief on the object\n"
    "  --json                    print the result as JSON\n";

}  // namespace

int localize_codebook(Session& s, int argc, char** argv) {
    Args a(argc, argv, 2,
           {{"--method"}, {"--tactile"}, {"--object"}, {"--background"}, {"--calibration"}, {"--codebook"}, {"--object-units"},
            {"--topk"}, {"--render"}, {"--json", false}});
    if (a.help()) {
        std::fputs(kHelp, stdout);
        return 0;
    }
    const std::string tactile = a.required("--tactile"), object = a.required("--object");
    const int topk = a.get("--topk") ? int(parse_numbers(*a.get("--topk"), 1, "--topk")[0]) : 5;
    if (topk < 1 || topk > 64) throw UsageError("--topk must be 1..64");
    const api::TactileImage frame = api::load_tactile_image(tactile);
    std::optional<api::TactileImage> empty;
    const std::string background = a.get("--background").value_or("");
    if (!background.empty()) empty = api::load_tactile_image(background);
    api::GelShapeOptions go;
    go.calibration = a.get("--calibration").value_or("");
    api::TrackerOptions to;
    to.codebook_cache = a.get("--codebook").value_or("");
    if (auto u = a.get("--object-units")) to.object_units = parse_numbers(*u, 1, "--object-units")[0];
    to.mode_radius_mm = 5;

    const auto t0 = std::chrono::steady_clock::now();
    api::GelShapeReader reader(s.gpu(), go);
    const api::GelShape shape = read_gel_shape(reader, tactile, frame, empty ? &*empty : nullptr, background);
    api::Tracker tracker(s.gpu(), object, to);
    const auto t1 = std::chrono::steady_clock::now();
    tracker.shape_term(shape);  // renders (or reads) the codebook once
    const auto t2 = std::chrono::steady_clock::now();
    const api::TrackerEstimate e = tracker.evaluate_window({}, {}, nullptr, {&shape});
    const auto t3 = std::chrono::steady_clock::now();
    auto ms = [](auto x, auto y) { return std::chrono::duration<double, std::milli>(y - x).count(); };
    if (auto r = a.get("--render")) api::render_tracker_png(*r, tracker, {e}, {"codebook: " + tactile});

    const size_t k = std::min<size_t>(size_t(topk), e.modes.size());
    if (a.flag("--json")) {
        nlohmann::json modes = nlohmann::json::array();
        for (size_t i = 0; i < k; ++i) modes.push_back({{"contact", e.modes[i].contact}, {"probability", e.modes[i].probability}});
        nlohmann::json j{{"method", "codebook"}, {"object", object}, {"tactile", tactile}, {"contact", e.contact},
                         {"pose_contact", e.pose_contact}, {"pose", {{"R", e.pose.R}, {"t", e.pose.t}}}, {"modes", modes},
                         {"mass_within_5mm", e.mass_within_5mm}, {"press_mm", *std::max_element(shape.depth_mm.begin(), shape.depth_mm.end())},
                         {"timings_ms", {{"shape_and_surface", ms(t0, t1)}, {"codebook", ms(t1, t2)}, {"score_and_belief", ms(t2, t3)}}}};
        if (auto r = a.get("--render")) j["outputs"]["render"] = *r;
        std::printf("%s\n", j.dump(2).c_str());
        return 0;
    }
    std::printf("method    codebook (render-and-compare alone, no network)\n");
    std::printf("object    %s: %zu hypotheses (%d spins), samples %.2f mm apart\n", object.c_str(), tracker.sample_points().size() / 3 * size_t(tracker.n_spin()),
                tracker.n_spin(), tracker.spacing_mm());
    std::printf("contact   %.3f %.3f %.3f (the belief's %.0f%% within 5 mm)\n", e.contact[0], e.contact[1], e.contact[2],
                100 * e.mass_within_5mm);
    for (size_t i = 0; i < k; ++i)
        std::printf("mode %zu    %.3f %.3f %.3f  p = %.3f\n", i + 1, e.modes[i].contact[0], e.modes[i].contact[1], e.modes[i].contact[2],
                    e.modes[i].probability);
    std::printf("time      shape and surface %.0f ms, codebook %.0f ms (once per object; cached with --codebook), touch %.0f ms\n",
                ms(t0, t1), ms(t1, t2), ms(t2, t3));
    if (auto r = a.get("--render")) std::printf("wrote     %s\n", r->c_str());
    return 0;
}

}  // namespace vtloc::cli
