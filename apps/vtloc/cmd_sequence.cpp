// vtloc sequence: several touches and the robot's motions between them -> the
// sensor's pose on the object after each touch (SPEC section 6, api::Tracker).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "apps/vtloc/report.h"
#include "engine/io/touch_sequence.h"

namespace vtloc::cli {

namespace {

const char* kHelp =
    "usage: vtloc sequence --object FILE --touches SEQ.json [options]\n"
    "\n"
    "Localisation from several touches (SPEC section 6): the online multi-touch filter follows\n"
    "a belief over the sensor's pose on the object's surface from the geometry of the touches\n"
    "and the motions between them, and (unless --geometry-only) each touch's network heat-map.\n"
    "It prints, after each touch, the contact (the Bayes estimate), the most likely pose and the\n"
    "modes of the belief.\n"
    "\n"
    "  --object FILE             a mesh (.glb .gltf .obj .off .stl .ply; sampled densely: the\n"
    "                            surface is exact) or a cloud with normals (.ply .xyz/.csv/.txt)\n"
    "  --touches SEQ.json        {\"format\": \"vtloc-touches/2\", \"motion\": \"relative\" | \"flange\",\n"
    "                            \"touches\": [{\"tactile\": \"a.png\"}, {\"tactile\": \"b.png\",\n"
    "                            \"motion\": M}, ...]}; relative: M = this touch's sensor pose in the\n"
    "                            previous one's frame, a 4x4 matrix or {\"Q\": 3x3, \"q\": [x, y, z]};\n"
    "                            flange: every touch has \"flange\": the flange pose in the robot's\n"
    "                            frame (4x4), and the file or --tool gives \"tool\" (flange to sensor).\n"
    "                            Paths relative to the file; units those of the robot (mm)\n"
    "  --tool M16                the flange-to-sensor transform, 16 numbers row-major\n"
    "  --object-units S          multiply the object file's coordinates by S to get the robot's\n"
    "                            units (a glTF in metres with a robot in mm: 1000; default 1)\n"
    "  --geometry-only           no network term (no model is loaded)\n"
    "  --window W                touches scored exactly, older ones through a prior (default 8)\n"
    "  --odometry-noise MM,DEG   how far each motion may be off (std per motion: translation mm,\n"
    "                            rotation degrees); the filter widens its widths and, with\n"
    "                            --render-compare, aligns the earlier touches' shapes within them\n"
    "  --render-compare          each frame's gel shape (as vtloc shape reads it) compared with what\n"
    "                            the object would press at every hypothesis and at the refined\n"
    "                            poses (SPEC 9, \"MidasTouch-style\"); the object's codebook is\n"
    "                            rendered at the first touch (seconds) unless --codebook-cache has it\n"
    "  --background EMPTY.png    with --render-compare: the sensor's empty frame (default: the\n"
    "                            calibration's)\n"
    "  --calibration C           with --render-compare: a Taxim-style calibration (default: the\n"
    "                            shipped GelSight one)\n"
    "  --rendered                with --render-compare: the reader for frames vtloc synth rendered\n"
    "                            (as vtloc shape --rendered)\n"
    "  --codebook-cache FILE     with --render-compare: read the object's codebook from FILE when it\n"
    "                            was made for this object and options (else an error), write it after\n"
    "                            the first render\n"
    "  --model M                 weight file for the network term (default: the shipped model)\n"
    "  --json                    print the result as JSON (each touch's contact, pose and modes; the\n"
    "                            hypotheses, and the tracker's device and host bytes after the last)\n"
    "  --render OUT.png          the belief after each touch, side by side on the object\n"
    "  --threads N               host threads the filter's estimates and tables (and with\n"
    "                            --render-compare the reader's) are built on, 0..256 (default 0:\n"
    "                            up to 4; the outputs do not depend on it)\n"
    "  --profile                 each touch's times: add_touch and estimate (wall clock, ms) and\n"
    "                            the GPU step per node (run node by node with timestamps: slower,\n"
    "                            the same outputs)\n"
    "\n"
    "Exit status: 0 ok, 1 bad input or runtime error, 2 usage error.\n";

api::Motion to_motion(const Rigid& m) { return api::Motion{m.R, m.t}; }

nlohmann::json matrix_json(const api::Motion& m) {
    return nlohmann::json::array({{m.R[0], m.R[1], m.R[2], m.t[0]},
                                  {m.R[3], m.R[4], m.R[5], m.t[1]},
                                  {m.R[6], m.R[7], m.R[8], m.t[2]},
                                  {0, 0, 0, 1}});
}

}  // namespace

int cmd_sequence(Session& s, int argc, char** argv) {
    std::vector<OptionSpec> specs{{"--object"}, {"--touches"}, {"--tool"}, {"--object-units"}, {"--geometry-only", false},
                                  {"--window"}, {"--model"}, {"--json", false}, {"--render"}, {"--odometry-noise"},
                                  {"--render-compare", false}, {"--background"}, {"--calibration"}, {"--rendered", false},
                                  {"--codebook-cache"}, {"--profile", false}, {"--threads"}};
    Args a(argc, argv, 2, specs);
    if (a.help()) {
        std::fputs(kHelp, stdout);
        return 0;
    }
    const std::string object_path = a.required("--object");
    const std::string touches_path = a.required("--touches");
    io::TouchSequence file = io::read_touch_sequence(touches_path);
    if (auto t = a.get("--tool")) {
        const std::vector<double> v = parse_numbers(*t, 16, "--tool");
        std::array<double, 16> rows{};
        std::copy(v.begin(), v.end(), rows.begin());
        try {
            file.tool = rigid_from_rows(rows, "--tool");
        } catch (const Error& e) {
            throw UsageError(e.what());
        }
    }
    std::vector<std::optional<api::Motion>> motions;
    for (const std::optional<Rigid>& m : file.relative_motions(touches_path)) motions.push_back(m ? std::optional(to_motion(*m)) : std::nullopt);
    api::TrackerOptions to;
    to.window = a.integer("--window", to.window, 1, 64);
    if (a.get("--window") && size_t(to.window) > file.touches.size())
        throw UsageError("--window " + std::to_string(to.window) + " is longer than the " + std::to_string(file.touches.size()) +
                         " touches of " + touches_path);
    to.object_units = a.number("--object-units", 1.0);
    to.threads = a.integer("--threads", to.threads, 0, 256);
    const bool geometry_only = a.flag("--geometry-only");
    if (auto n = a.get("--odometry-noise")) {
        const std::vector<double> v = parse_numbers(*n, 2, "--odometry-noise");
        if (!(v[0] >= 0) || !(v[1] >= 0) || !std::isfinite(v[0]) || !std::isfinite(v[1]))
            throw UsageError("--odometry-noise: both widths must be finite and >= 0, got " + *n);
        to.odometry_mm = v[0], to.odometry_deg = v[1];
    }
    // Render-and-compare: the reader's options and the empty frame, checked before any work.
    const bool render_compare = a.flag("--render-compare");
    for (const char* opt : {"--background", "--calibration", "--codebook-cache"})
        if (!render_compare && a.get(opt)) throw UsageError(std::string(opt) + " is for --render-compare");
    if (!render_compare && a.flag("--rendered")) throw UsageError("--rendered is for --render-compare");
    std::optional<api::GelShapeReader> reader;
    std::optional<api::TactileImage> empty;
    const std::string background = a.get("--background").value_or("");
    if (render_compare) {
        api::GelShapeOptions go = a.flag("--rendered") ? api::GelShapeOptions::rendered_frames() : api::GelShapeOptions{};
        go.calibration = a.get("--calibration").value_or("");
        go.threads = to.threads;
        reader.emplace(s.gpu(), go);
        if (!background.empty()) empty = api::load_tactile_image(background);
        to.codebook_cache = a.get("--codebook-cache").value_or("");
    }

    // Every touch's frame looked at before the model, the object and the tracker are made (decoded,
    // and with render-and-compare checked as the gel shape's reader takes it, without the GPU): a bad
    // frame late in the file is refused without that wait. Nothing is kept: the loop below decodes
    // each again, so memory stays flat over a long file.
    const auto where = [&](size_t i) { return " (touch " + std::to_string(i + 1) + " of " + touches_path + ")"; };
    for (size_t i = 0; i < file.touches.size(); ++i) {
        const std::string& f = file.touches[i].tactile;
        if (geometry_only && !reader) {
            if (!std::filesystem::exists(f)) throw api::Error(f + ": no such file" + where(i));
            continue;
        }
        const api::TactileImage im = api::load_tactile_image(f);
        if (reader) check_gel_frame(*reader, f, im, empty ? &*empty : nullptr, background, where(i));
    }

    const bool profile = a.flag("--profile");
    to.profile = profile;
    api::Tracker tracker(s.gpu(), object_path, to);
    // Every motion checked against the object before the first touch (a unit mismatch is refused
    // at once, not at the first long hop), and before the model is loaded.
    for (size_t i = 0; i < motions.size(); ++i)
        if (motions[i]) {
            try {
                tracker.check_motion(*motions[i], int(i + 1));
            } catch (const api::Error& e) {
                throw api::Error(std::string(e.what()) + " (" + touches_path + ")");
            }
        }
    std::optional<api::Model> model;
    std::optional<api::Object> object;
    std::string model_file;
    if (!geometry_only) {
        model_file = a.get("--model").value_or(default_model_path());
        model.emplace(load_model(s, model_file, api::Backend::Gpu));
        object = model->encode_object(object_path);
    }
    std::vector<api::TrackerEstimate> steps;
    nlohmann::json jt = nlohmann::json::array();
    const bool json = a.flag("--json");
    if (!json) {
        if (model) print_model(model->info(), is_shipped_random_model(model_file));
        std::printf("object    %s: hypotheses %zu surface samples x %d spins (%.2f mm apart), %.1f MiB on the GPU, "
                    "%.1f MiB of host memory%s\n",
                    object_path.c_str(), tracker.sample_points().size() / 3, tracker.n_spin(), tracker.spacing_mm(),
                    double(tracker.device_bytes()) / 1048576.0, double(tracker.host_bytes()) / 1048576.0,
                    geometry_only ? (render_compare ? ", geometry + render-and-compare" : ", geometry only")
                                  : (render_compare ? ", network + render-and-compare" : ""));
    }
    for (size_t i = 0; i < file.touches.size(); ++i) {
        const std::string& f = file.touches[i].tactile;
        std::optional<api::TactileImage> im;
        if (model || reader) im = api::load_tactile_image(f);
        std::optional<api::TouchResult> r;
        if (model) r = model->localize(*object, *im);
        std::optional<api::GelShape> shape;
        if (reader) shape = read_gel_shape(*reader, f, *im, empty ? &*empty : nullptr, background, where(i));
        const auto t0 = std::chrono::steady_clock::now();
        tracker.add_touch(motions[i], r ? &*r : nullptr, object ? &*object : nullptr, shape ? &*shape : nullptr);
        const auto t1 = std::chrono::steady_clock::now();
        const api::TrackerEstimate e = tracker.estimate();
        const auto t2 = std::chrono::steady_clock::now();
        steps.push_back(e);
        nlohmann::json modes = nlohmann::json::array();
        for (const api::TrackerMode& m : e.modes) modes.push_back({{"contact", point_json(m.contact)}, {"probability", m.probability}});
        nlohmann::json t{{"tactile", file.touches[i].tactile}, {"contact", point_json(e.contact)}, {"pose", matrix_json(e.pose)},
                         {"pose_contact", point_json(e.pose_contact)}, {"modes", modes}, {"mass_within_5mm", e.mass_within_5mm},
                         {"fit", e.fit}, {"pose_terms", e.pose_terms}};
        if (file.flange)  // the object in the robot's frame: flange * tool * inverse(sensor pose in the object)
            t["object_in_robot"] = matrix_json(api::compose(to_motion(compose(*file.touches[i].flange, *file.tool)), api::inverse(e.pose)));
        const auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
        const std::vector<std::pair<std::string, double>> nodes = profile ? tracker.step_nodes() : decltype(nodes){};
        if (profile) {
            nlohmann::json jn = nlohmann::json::array();
            for (const auto& [name, t_ms] : nodes) jn.push_back({{"node", name}, {"ms", t_ms}});
            t["ms"] = {{"add_touch", ms(t0, t1)}, {"estimate", ms(t1, t2)}, {"nodes", jn}};
        }
        jt.push_back(t);
        if (!json) {
            std::printf("touch %-3zu %s\n          contact %s, belief within 5 mm %.2f; best mode %s (p %.2f)\n", i + 1,
                        file.touches[i].tactile.c_str(), point_str(e.contact).c_str(), e.mass_within_5mm,
                        point_str(e.modes.empty() ? e.contact : e.modes[0].contact).c_str(),
                        e.modes.empty() ? 0.0 : e.modes[0].probability);
            if (profile) {
                std::printf("          add_touch %.1f ms, estimate %.1f ms; GPU step by node:", ms(t0, t1), ms(t1, t2));
                for (const auto& [name, t_ms] : nodes) std::printf(" %s %.2f", name.c_str(), t_ms);
                std::printf("\n");
            }
        }
    }
    nlohmann::json outputs = nlohmann::json::object();
    if (auto p = a.get("--render")) {
        std::vector<std::string> captions;
        for (size_t i = 0; i < steps.size(); ++i) captions.push_back("belief after touch " + std::to_string(i + 1));
        api::render_tracker_png(*p, tracker, steps, captions);
        outputs["render"] = *p;
        if (!json) std::printf("wrote     %s\n", p->c_str());
    }
    if (json) {
        nlohmann::json j{{"object", object_path}, {"geometry_only", geometry_only}, {"render_compare", render_compare},
                         {"odometry_noise", {to.odometry_mm, to.odometry_deg}}, {"touches", jt}, {"outputs", outputs},
                         {"hypotheses", tracker.sample_points().size() / 3 * size_t(tracker.n_spin())},
                         // After the last touch: what the tracker holds then (its tables and graphs).
                         {"memory", {{"device_bytes", tracker.device_bytes()}, {"host_bytes", tracker.host_bytes()}}}};
        if (model) j["model"] = model_json(model->info(), is_shipped_random_model(model_file));
        if (s.context) j["device"] = s.context->device().name;
        std::printf("%s\n", j.dump(2).c_str());
    }
    return 0;
}

}  // namespace vtloc::cli
