// vtloc sequence: several touches and the robot's motions between them -> the
// sensor's pose on the object after each touch (SPEC section 6, api::Tracker).
#include <cstdio>
#include <fstream>

#include "apps/vtloc/report.h"

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
    "  --model M                 weight file for the network term (default: the shipped model)\n"
    "  --json                    print the result as JSON\n"
    "  --render OUT.png          the belief after each touch, side by side on the object\n"
    "\n"
    "Exit status: 0 ok, 1 bad input or runtime error, 2 usage error.\n";

struct Touch {
    std::string image;
    std::optional<api::Motion> motion;  // relative, from the previous touch
    std::optional<api::Motion> flange;  // absolute, robot frame
};

// A 4x4 matrix (rows) or {"Q": 3x3, "q": [3]} as a rigid motion.
api::Motion parse_motion(const nlohmann::json& m, const std::string& where) {
    api::Motion out;
    auto num = [&](const nlohmann::json& v) {
        if (!v.is_number()) throw api::Error(where + ": expected a number, got " + v.dump());
        return v.get<double>();
    };
    if (m.is_array() && m.size() == 3 && m[0].is_number())
        throw api::Error(where + ": a translation [dx, dy, dz] is the old translation-only format; motions are full "
                                 "rigid motions now (a 4x4 matrix or {\"Q\": 3x3, \"q\": [x, y, z]})");
    if (m.is_array() && m.size() == 4) {
        for (int r = 0; r < 4; ++r) {
            if (!m[size_t(r)].is_array() || m[size_t(r)].size() != 4) throw api::Error(where + ": a 4x4 matrix needs 4 rows of 4");
            for (int c = 0; c < 4; ++c) {
                const double v = num(m[size_t(r)][size_t(c)]);
                if (r == 3 && v != (c == 3 ? 1.0 : 0.0)) throw api::Error(where + ": the last row must be 0 0 0 1");
                if (r < 3 && c < 3) out.R[size_t(r * 3 + c)] = v;
                if (r < 3 && c == 3) out.t[size_t(r)] = v;
            }
        }
        return out;
    }
    if (m.is_object() && m.contains("Q") && m.contains("q")) {
        const nlohmann::json &Q = m["Q"], &q = m["q"];
        if (!Q.is_array() || Q.size() != 3 || !q.is_array() || q.size() != 3)
            throw api::Error(where + ": \"Q\" must be 3 rows of 3 and \"q\" 3 numbers");
        for (int r = 0; r < 3; ++r) {
            if (!Q[size_t(r)].is_array() || Q[size_t(r)].size() != 3) throw api::Error(where + ": \"Q\" must be 3 rows of 3");
            for (int c = 0; c < 3; ++c) out.R[size_t(r * 3 + c)] = num(Q[size_t(r)][size_t(c)]);
            out.t[size_t(r)] = num(q[size_t(r)]);
        }
        return out;
    }
    throw api::Error(where + ": a motion is a 4x4 matrix or {\"Q\": 3x3, \"q\": [x, y, z]}");
}

struct TouchFile {
    std::vector<Touch> touches;
    bool flange = false;
    std::optional<api::Motion> tool;
};

TouchFile read_touch_file(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw api::Error(path + ": cannot open");
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception&) {
        throw api::Error(path + ": not valid JSON");
    }
    if (!j.is_object() || !j.contains("touches") || !j["touches"].is_array())
        throw api::Error(path + ": expected {\"format\": \"vtloc-touches/2\", \"touches\": [...]}");
    if (!j.contains("format"))
        throw api::Error(path + ": no \"format\": this is the old translation-only touches file; give "
                                "\"format\": \"vtloc-touches/2\" with full rigid motions (vtloc sequence --help)");
    if (j["format"] != "vtloc-touches/2")
        throw api::Error(path + ": format " + j["format"].dump() + " is not \"vtloc-touches/2\"");
    TouchFile f;
    const std::string kind = j.value("motion", std::string("relative"));
    if (kind != "relative" && kind != "flange") throw api::Error(path + ": \"motion\" must be \"relative\" or \"flange\"");
    f.flange = kind == "flange";
    if (j.contains("tool")) f.tool = parse_motion(j["tool"], path + ": tool");
    const std::filesystem::path base = std::filesystem::path(path).parent_path();
    for (size_t i = 0; i < j["touches"].size(); ++i) {
        const nlohmann::json& t = j["touches"][i];
        const std::string where = path + ": touch " + std::to_string(i + 1);
        if (!t.is_object() || !t.contains("tactile") || !t["tactile"].is_string())
            throw api::Error(where + " needs a \"tactile\" image path");
        Touch touch{(base / t["tactile"].get<std::string>()).lexically_normal().string(), std::nullopt, std::nullopt};
        if (f.flange) {
            if (!t.contains("flange")) throw api::Error(where + " needs \"flange\" (the file's motions are flange poses)");
            touch.flange = parse_motion(t["flange"], where + ": flange");
        } else if (t.contains("motion")) {
            if (i == 0) throw api::Error(where + ": the first touch has no previous one to move from; drop its motion");
            touch.motion = parse_motion(t["motion"], where + ": motion");
        } else if (i > 0) {
            throw api::Error(where + " needs a \"motion\" from the previous touch");
        }
        f.touches.push_back(touch);
    }
    if (f.touches.empty()) throw api::Error(path + ": no touches");
    return f;
}

nlohmann::json matrix_json(const api::Motion& m) {
    return nlohmann::json::array({{m.R[0], m.R[1], m.R[2], m.t[0]},
                                  {m.R[3], m.R[4], m.R[5], m.t[1]},
                                  {m.R[6], m.R[7], m.R[8], m.t[2]},
                                  {0, 0, 0, 1}});
}

}  // namespace

int cmd_sequence(Session& s, int argc, char** argv) {
    std::vector<OptionSpec> specs{{"--object"}, {"--touches"}, {"--tool"}, {"--object-units"}, {"--geometry-only", false},
                                  {"--window"}, {"--model"}, {"--json", false}, {"--render"}};
    Args a(argc, argv, 2, specs);
    if (a.help()) {
        std::fputs(kHelp, stdout);
        return 0;
    }
    const std::string object_path = a.required("--object");
    const std::string touches_path = a.required("--touches");
    TouchFile file = read_touch_file(touches_path);
    if (auto t = a.get("--tool")) {
        const std::vector<double> v = parse_numbers(*t, 16, "--tool");
        nlohmann::json m = nlohmann::json::array();
        for (int r = 0; r < 4; ++r) m.push_back({v[size_t(4 * r)], v[size_t(4 * r + 1)], v[size_t(4 * r + 2)], v[size_t(4 * r + 3)]});
        file.tool = parse_motion(m, "--tool");
    }
    if (file.flange && !file.tool) throw api::Error(touches_path + ": flange poses need the tool transform (\"tool\" or --tool)");
    std::vector<std::optional<api::Motion>> motions(file.touches.size());
    if (file.flange) {
        std::vector<api::Motion> flange;
        for (const Touch& t : file.touches) flange.push_back(*t.flange);
        const std::vector<api::Motion> rel = api::motions_from_flange_poses(flange, *file.tool);
        for (size_t i = 1; i < file.touches.size(); ++i) motions[i] = rel[i - 1];
    } else {
        for (size_t i = 0; i < file.touches.size(); ++i) motions[i] = file.touches[i].motion;
    }
    api::TrackerOptions to;
    to.window = a.integer("--window", to.window, 1, 64);
    to.object_units = a.number("--object-units", 1.0);
    const bool geometry_only = a.flag("--geometry-only");

    std::optional<api::Model> model;
    std::optional<api::Object> object;
    std::string model_file;
    if (!geometry_only) {
        model_file = a.get("--model").value_or(default_model_path());
        model.emplace(load_model(s, model_file, api::Backend::Gpu));
        object = model->encode_object(object_path);
    }
    api::Tracker tracker(s.gpu(), object_path, to);
    std::vector<api::TrackerEstimate> steps;
    nlohmann::json jt = nlohmann::json::array();
    const bool json = a.flag("--json");
    if (!json) {
        if (model) print_model(model->info(), is_shipped_random_model(model_file));
        std::printf("object    %s: hypotheses %zu surface samples x %d spins (%.2f mm apart), %.1f MiB on the GPU%s\n",
                    object_path.c_str(), tracker.sample_points().size() / 3, tracker.n_spin(), tracker.spacing_mm(),
                    double(tracker.device_bytes()) / 1048576.0, geometry_only ? ", geometry only" : "");
    }
    for (size_t i = 0; i < file.touches.size(); ++i) {
        std::optional<api::TouchResult> r;
        if (model) {
            const api::TactileImage im = api::load_tactile_image(file.touches[i].image);
            r = model->localize(*object, im);
        } else if (!std::filesystem::exists(file.touches[i].image)) {
            throw api::Error(file.touches[i].image + ": no such file (touch " + std::to_string(i + 1) + " of " + touches_path + ")");
        }
        tracker.add_touch(motions[i], r ? &*r : nullptr, object ? &*object : nullptr);
        const api::TrackerEstimate e = tracker.estimate();
        steps.push_back(e);
        nlohmann::json modes = nlohmann::json::array();
        for (const api::TrackerMode& m : e.modes) modes.push_back({{"contact", point_json(m.contact)}, {"probability", m.probability}});
        nlohmann::json t{{"tactile", file.touches[i].image}, {"contact", point_json(e.contact)}, {"pose", matrix_json(e.pose)},
                         {"pose_contact", point_json(e.pose_contact)}, {"modes", modes}, {"mass_within_5mm", e.mass_within_5mm}};
        if (file.flange)  // the object in the robot's frame: flange * tool * inverse(sensor pose in the object)
            t["object_in_robot"] = matrix_json(api::compose(api::compose(*file.touches[i].flange, *file.tool), api::inverse(e.pose)));
        jt.push_back(t);
        if (!json)
            std::printf("touch %-3zu %s\n          contact %s, belief within 5 mm %.2f; best mode %s (p %.2f)\n", i + 1,
                        file.touches[i].image.c_str(), point_str(e.contact).c_str(), e.mass_within_5mm,
                        point_str(e.modes.empty() ? e.contact : e.modes[0].contact).c_str(),
                        e.modes.empty() ? 0.0 : e.modes[0].probability);
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
        nlohmann::json j{{"object", object_path}, {"geometry_only", geometry_only}, {"touches", jt}, {"outputs", outputs}};
        if (model) j["model"] = model_json(model->info(), is_shipped_random_model(model_file));
        if (s.context) j["device"] = s.context->device().name;
        std::printf("%s\n", j.dump(2).c_str());
    }
    return 0;
}

}  // namespace vtloc::cli
