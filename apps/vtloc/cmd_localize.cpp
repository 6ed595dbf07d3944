// vtloc localize: one touch on one object.
#include <chrono>
#include <cstdio>

#include "apps/vtloc/report.h"

namespace vtloc::cli {

namespace {

const char* kHelp =
    "usage: vtloc localize [--model M] --tactile IMG (--object FILE | --depth D.png --intrinsics K) [options]\n"
    "\n"
    "Localises one touch: where on the object the tactile image was taken, with a\n"
    "heat-map over the object's points.\n"
    "\n"
    "  --method network|codebook the model (default), or render-and-compare alone (SPEC 9; see\n"
    "                            vtloc localize --method codebook --help)\n"
    "  --model M                 weight file (default: the shipped models/vtloc-lite-everyday)\n"
    "  --tactile IMG             tactile image (PNG, JPEG, ...; RGB, at least 8x8)\n"
    "%s"
    "  --candidates F            candidate contact points (.ply, or x,y,z text rows);\n"
    "                            default: the object's points\n"
    "%s"
    "  --json                    print the result as JSON\n"
    "  --heatmap OUT.ply         write the heat-map as a PLY (contact_prob + colour)\n"
    "  --render OUT.png          write a picture of the heat-map\n"
    "  --dump DIR                write every intermediate tensor (SPEC section 8 names) to\n"
    "                            DIR/tensors.safetensors and the object cloud to DIR/cloud.ply,\n"
    "                            and print the weights_tools.golden command that cross-checks them\n"
    "  --profile                 per-node GPU times (with --json)\n"
    "\n"
    "Coordinates are in the object file's units. Exit status: 0 ok, 1 bad input or\n"
    "runtime error, 2 usage error.\n";

std::string golden_command(const std::string& model, const std::string& tactile, const std::string& cloud,
                           const Args& a, const std::string& out) {
    std::string cmd = "/usr/bin/python3 -m weights_tools.golden --weights " + model + " --tactile " + tactile +
                      " --cloud " + cloud;
    if (auto c = a.get("--candidates")) cmd += " --candidates " + *c;
    if (auto n = a.get("--iters")) cmd += " --iters " + *n;
    if (auto k = a.get("--topk")) cmd += " --K " + *k;
    if (auto s = a.get("--symmetry-axis")) cmd += " --symmetry " + *s + "," + *a.get("--symmetry-order");
    if (auto m = a.get("--mm-per-px")) cmd += " --mm-per-px " + *m;
    return cmd + " -o " + out;
}

// What the outputs and the report need of one localize run.
struct Run {
    const Args& a;
    const std::string &tactile_path, &object_path, &candidates, &model_file;
    const api::TactileImage& image;
    const api::ModelInfo& info;
    const api::Object& object;
    const api::TouchResult& r;
    api::Backend backend;
    double encode_ms;
};

// --heatmap, --render and --dump; `golden` gets the cross-check command of a dump.
nlohmann::json write_outputs(const Run& run, std::string& golden) {
    const Args& a = run.a;
    nlohmann::json outputs = nlohmann::json::object();
    write_heatmap_option(a, run.object, run.r.heatmap, outputs);
    if (auto p = a.get("--render")) {
        api::RenderOptions ro;
        ro.contact = run.r.contact;
        ro.tactile = &run.image;
        ro.caption = run.info.name + (is_shipped_random_model(run.model_file) ? " (RANDOM weights)" : "") + ": " +
                     run.tactile_path + " on " + run.object_path;
        api::render_heatmap_png(*p, run.object, run.r.heatmap, ro);
        outputs["render"] = *p;
    }
    if (const auto dump = a.get("--dump")) {
        make_folder(*dump);
        const std::string tensors = (std::filesystem::path(*dump) / "tensors.safetensors").string();
        const std::string cloud = (std::filesystem::path(*dump) / "cloud.ply").string();
        api::save_tensors(tensors, run.r.tensors, run.info.config_json);
        api::write_heatmap_ply(cloud, run.object, run.r.heatmap);
        golden = golden_command(run.model_file, run.tactile_path, cloud, a,
                                (std::filesystem::path(*dump) / "golden.safetensors").string());
        outputs["dump"] = {{"tensors", tensors}, {"cloud", cloud}, {"golden_command", golden}};
    }
    return outputs;
}

void print_json(const Session& s, const Run& run, const nlohmann::json& outputs) {
    const bool random = is_shipped_random_model(run.model_file);
    nlohmann::json j{{"model", model_json(run.info, random)},
                     {"backend", run.backend == api::Backend::Gpu ? "gpu" : "cpu"},
                     {"object", object_json(run.object, run.candidates)},
                     {"tactile", {{"path", run.tactile_path}, {"width", run.image.width}, {"height", run.image.height}}},
                     {"outputs", outputs}};
    if (s.context) j["device"] = s.context->device().name;
    j.update(touch_json(run.r));
    j["timings_ms"]["encode_ms"] = run.encode_ms;
    std::printf("%s\n", j.dump(2).c_str());
}

void print_text(const Session& s, const Run& run, const nlohmann::json& outputs, const std::string& golden) {
    const api::Object& object = run.object;
    print_model(run.info, is_shipped_random_model(run.model_file));
    std::printf("device    %s\n", s.context ? s.context->device().name.c_str() : "CPU reference (--backend cpu)");
    std::printf("object    %s: %zu points%s, %zu candidates%s\n", run.object_path.c_str(), object.cloud().size(),
                object.normals_estimated() ? " (normals estimated)" : "", object.candidate_count(),
                run.candidates.empty() ? " (its points)" : (" from " + run.candidates).c_str());
    std::printf("tactile   %s (%dx%d)\n", run.tactile_path.c_str(), run.image.width, run.image.height);
    print_touch(run.r);
    std::printf("time      encode object %.1f ms, touch %.1f ms%s\n", run.encode_ms, run.r.timings.wall_ms,
                s.context ? " (a first run of a shape includes shader compilation)" : "");
    for (auto& [what, path] : outputs.items())
        if (what != "dump") std::printf("wrote     %s\n", path.get<std::string>().c_str());
    if (outputs.contains("dump")) {
        std::printf("wrote     %s\n          %s\n", outputs["dump"]["tensors"].get<std::string>().c_str(),
                    outputs["dump"]["cloud"].get<std::string>().c_str());
        std::printf("cross-check with the PyTorch reference:\n  %s\n", golden.c_str());
    }
}

}  // namespace

int cmd_localize(Session& s, int argc, char** argv) {
    // --method codebook has options of its own (localize_codebook.cpp).
    for (int i = 2; i + 1 < argc; ++i)
        if (std::string(argv[i]) == "--method") {
            const std::string m = argv[i + 1];
            if (m == "codebook") return localize_codebook(s, argc, argv);
            if (m != "network") throw UsageError("--method must be network (the model, default) or codebook (render-and-compare)");
        }
    std::vector<OptionSpec> specs{{"--method"}, {"--model"},     {"--tactile"}, {"--candidates"},
                                  {"--json", false}, {"--heatmap"}, {"--render"}, {"--dump"},
                                  {"--profile", false}};
    for (OptionSpec& o : touch_option_specs()) specs.push_back(o);
    for (OptionSpec& o : object_option_specs()) specs.push_back(o);
    Args a(argc, argv, 2, specs);
    if (a.help()) {
        std::printf(kHelp, kObjectOptionsHelp, kTouchOptionsHelp);
        return 0;
    }
    const std::string tactile_path = a.required("--tactile"), object_path = object_label(a);
    if (object_path.empty()) throw UsageError("give --object FILE or --depth D.png --intrinsics fx,fy,cx,cy");
    const std::string candidates = a.get("--candidates").value_or("");
    api::LocalizeOptions opt = touch_options(a);
    opt.profile = a.flag("--profile");
    opt.keep_tensors = a.get("--dump").has_value();
    const bool json_out = a.flag("--json");
    const std::string model_path = a.get("--model").value_or("");

    const std::string model_file = model_path.empty() ? default_model_path() : model_path;
    api::TactileImage image = api::load_tactile_image(tactile_path);  // before Vulkan starts: fail fast
    api::Model model = load_model(s, model_file, opt.backend);
    const api::ModelInfo& info = model.info();

    auto t0 = std::chrono::steady_clock::now();
    api::Object object = encode_cli_object(model, a, candidates, opt.backend);
    double encode_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    api::TouchResult r = model.localize(object, image, opt);

    const Run run{a, tactile_path, object_path, candidates, model_file, image, info, object, r, opt.backend, encode_ms};
    std::string golden;
    const nlohmann::json outputs = write_outputs(run, golden);
    if (json_out) print_json(s, run, outputs);
    else print_text(s, run, outputs, golden);
    return 0;
}

}  // namespace vtloc::cli
