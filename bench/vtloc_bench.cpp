// vtloc-bench: the whole model on one device - end to end, per stage, per
// node, per ILU iteration, cached objects, batches, memory, the point branch
// over cloud sizes - against the device's own fma peak, optionally on the CPU
// reference too. Prints a table; --json and --plot write the report.
// Run with --help for the options; bench/README.md describes the JSON.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "bench/model_bench.h"
#include "bench/probe.h"
#include "bench/report.h"
#include "bench/gel_bench.h"
#include "engine/tour_cycle.h"
#include "bench/tracker_bench.h"
#include "engine/io/touch_sequence.h"
#include "bench/validation.h"
#include "bench/fps_variants.h"
#include "bench/ilu_variants.h"
#include "bench/versus.h"
#include "base/error.h"
#include "base/python.h"
#include "base/shipped.h"
#include "engine/io/image.h"
#include "engine/io/object.h"
#include "engine/model/model_config.h"
#include "engine/ops/tactile_preprocess.h"
#include "runtime/context.h"
#include "runtime/device_profile.h"
#include "bench/plan.h"

#ifndef VTLOC_SOURCE_DIR
#define VTLOC_SOURCE_DIR ""
#endif
#ifndef VTLOC_PYTHON
#define VTLOC_PYTHON "python3"
#endif

using namespace vtloc;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

const char* kUsage = R"(usage: vtloc-bench [options]
  --weights FILE       weight file (default: the shipped default model, models/vtloc-lite-everyday.safetensors)
  --config NAME        instead: random weights of a named config (vtloc-r18, vtloc-mcr, vtloc-tiny,
                       vtloc-mcr-tiny), exported once by weights_tools (python3 + torch; VTLOC_PYTHON picks the interpreter) into
                       <bench dir>/bench-weights/NAME.safetensors
  --image FILE         tactile image (default: examples/touch_01.png)
  --object FILE        object mesh (.glb/.gltf) or PLY cloud (default: examples/mug.glb)
  --backend B          gpu (default), cpu (the CPU reference) or both (adds CPU/GPU ratios)
  --reps R             timed repetitions per measurement (default 20)
  --warmup W           untimed runs first (default 3)
  --profile-reps R     profiled runs for per-stage/per-node times (default 5)
  --cpu-reps R         repetitions on the CPU reference (default 2)
  --iters LIST         ILU N sweep (default 0,4,8,16,32,64)
  --stepped N          N of the one-dispatch-per-iteration ILU run (default 16; 0 skips)
  --batch LIST         batch sizes for throughput (default 1,4,16)
  --points LIST        point-branch sweep over cloud sizes (default 1024,4096,16384; needs a mesh)
  --tracker FILE       the multi-touch filter's stage: a touches file with its "object" (default:
                       examples/potato_tour.json), geometry only, on the GPU (--reps trackers) and
                       on the CPU reference (--cpu-reps)
  --tracker-touches N  touches per tracker run, the tour continued (default 12; the steady
                       state past the window is what is timed)
  --tracker-cycle C    how the tour goes on past its last touch: return (default: back over its
                       touches, then forward, every pose one on the object) or repeat (its motions
                       again from the last pose: off the object, the filter's rescue searched)
  --tracker-window W   the tracker's online window, 1-8 (default 8, the shipped one): the
                       touches scored exactly, older ones through the prior
  --no-tracker         skip the tracker stage
  --no-gel             skip the gel stage (SPEC 9): the gel's shape from one real frame, on the GPU
                       and the CPU reference, and render-and-compare on the tracker stage's object
                       (its codebook rendered once, one touch scored)
  --no-probe           skip the fma peak probe
  --plan-for FILE      only plan: the model's dispatches as the GPU of a device profile would get them
                       (bench/device_profiles/, or `vtloc devices --save-profile`), recorded on this
                       machine's device, never run: workgroups per dispatch per node and per stage
  --json FILE          write the report as JSON
  --plot FILE.png      draw latency over N and the per-stage breakdown
  --vs-pytorch         also time the PyTorch reference (weights_tools.bench_torch: float32, as many
                       threads as cores) on the same weights, image and cloud, in the same run, and
                       report engine/PyTorch ratios (VTLOC_PYTHON picks the interpreter)
  --pytorch-device D   where --vs-pytorch runs PyTorch: cpu (default) or cuda (the same GPU, where
                       torch has CUDA: each run synchronised)
The GPU is the default Vulkan device (VTLOC_DEVICE picks another: index or name).
)";

struct Args {
    std::string weights, config, image, object, backend = "gpu", json_path, plot_path;
    bench::ModelBenchOptions opt;
    int cpu_reps = 2, tracker_touches = 12, tracker_window = 8;
    std::string tracker_cycle = "return";
    bool probe = true, vs_pytorch = false, tracker = true, gel = true;
    std::string tracker_tour, plan_for, torch_device = "cpu";
};

std::vector<int64_t> int_list(const std::string& flag, const std::string& s) {
    std::vector<int64_t> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ',')) {
        char* end = nullptr;
        long long v = std::strtoll(item.c_str(), &end, 10);
        if (item.empty() || *end || v < 0) throw Error(flag + " takes a comma-separated list of non-negative integers, got '" + s + "'");
        out.push_back(v);
    }
    return out;
}

int one_int(const std::string& flag, const std::string& s, int lo) {
    std::vector<int64_t> v = int_list(flag, s);
    if (v.size() != 1 || v[0] < lo || v[0] > 1000000) throw Error(flag + " takes one integer >= " + std::to_string(lo) + ", got '" + s + "'");
    return int(v[0]);
}

Args parse(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        std::string f = argv[i];
        if (f == "--help" || f == "-h") {
            std::fputs(kUsage, stdout);
            std::exit(0);
        }
        if (f == "--no-probe") {
            a.probe = false;
            continue;
        }
        if (f == "--no-tracker") {
            a.tracker = false;
            continue;
        }
        if (f == "--no-gel") {
            a.gel = false;
            continue;
        }
        if (f == "--vs-pytorch") {
            a.vs_pytorch = true;
            continue;
        }
        if (i + 1 >= argc) throw Error("unknown option or missing value: " + f + " (see --help)");
        std::string v = argv[++i];
        if (f == "--weights") a.weights = v;
        else if (f == "--config") a.config = v;
        else if (f == "--plan-for") a.plan_for = v;
        else if (f == "--pytorch-device") {
            if (v != "cpu" && v != "cuda") throw Error("--pytorch-device: cpu or cuda, not '" + v + "'");
            a.torch_device = v;
        }
        else if (f == "--image") a.image = v;
        else if (f == "--object") a.object = v;
        else if (f == "--backend") a.backend = v;
        else if (f == "--reps") a.opt.reps = one_int(f, v, 1);
        else if (f == "--warmup") a.opt.warmup = one_int(f, v, 0);
        else if (f == "--profile-reps") a.opt.profile_reps = one_int(f, v, 1);
        else if (f == "--cpu-reps") a.cpu_reps = one_int(f, v, 1);
        else if (f == "--tracker") a.tracker_tour = v;
        else if (f == "--tracker-touches") a.tracker_touches = one_int(f, v, 2);
        else if (f == "--tracker-window") a.tracker_window = one_int(f, v, 1);
        else if (f == "--tracker-cycle") a.tracker_cycle = v;
        else if (f == "--stepped") a.opt.stepped_iters = one_int(f, v, 0);
        else if (f == "--json") a.json_path = v;
        else if (f == "--plot") a.plot_path = v;
        else if (f == "--iters" || f == "--batch") {
            std::vector<int> l;
            for (int64_t x : int_list(f, v)) l.push_back(int(x));
            (f == "--iters" ? a.opt.iters : a.opt.batches) = l;
        } else if (f == "--points") a.opt.points = int_list(f, v);
        else throw Error("unknown option " + f + " (see --help)");
    }
    if (a.backend != "gpu" && a.backend != "cpu" && a.backend != "both")
        throw Error("--backend takes gpu, cpu or both, got '" + a.backend + "'");
    if (!a.weights.empty() && !a.config.empty()) throw Error("give --weights or --config, not both");
    for (int n : a.opt.iters)
        if (n > 64) throw Error("--iters: N must be in 0..64, got " + std::to_string(n));
    if (a.opt.stepped_iters > 64) throw Error("--stepped: N must be in 0..64");
    if (!known_tour_cycle(a.tracker_cycle))
        throw Error("--tracker-cycle takes return or repeat, got '" + a.tracker_cycle + "'");
    if (a.tracker_window > 8) throw Error("--tracker-window: 1 to 8 touches, got " + std::to_string(a.tracker_window));
    if (a.tracker_touches <= a.tracker_window)
        throw Error("--tracker-touches (" + std::to_string(a.tracker_touches) + ") must exceed the tracker's window (" +
                    std::to_string(a.tracker_window) + "): the steady state past it is timed");
    return a;
}

fs::path exe_dir() {
    const fs::path exe = current_executable();
    return exe.empty() ? fs::path(".") : exe.parent_path();
}

// The repository holding models/ and examples/, found as the CLI finds it (the
// bench is not installed: no install folder).
fs::path data_dir() { return find_shipped_dir(shipped_dir_candidates(current_executable(), "", VTLOC_SOURCE_DIR)); }

// Random weights of a named config, exported by weights_tools once and cached.
std::string random_export(const std::string& name) {
    for (char c : name)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_'))
            throw Error("--config: '" + name + "' is not a config name");
    fs::path out = exe_dir() / "bench-weights" / (name + ".safetensors");
    if (fs::exists(out)) return out.string();
    fs::create_directories(out.parent_path());
    const fs::path tmp = out.string() + ".tmp";
    const std::string python = python_interpreter(VTLOC_PYTHON);
    const std::string cmd = "cd '" + data_dir().string() + "' && '" + python + "' -m weights_tools.export --config '" + name +
                            "' --seed 0 -o '" + tmp.string() + "' >&2";
    std::fprintf(stderr, "exporting random %s weights: %s\n", name.c_str(), cmd.c_str());
    if (std::system(cmd.c_str()) != 0 || !fs::exists(tmp))
        throw Error("could not export random weights for config '" + name +
                    "' (weights_tools needs python3 with torch); pass --weights FILE instead");
    fs::rename(tmp, out);
    return out.string();
}

std::string today() {
    std::time_t t = std::time(nullptr);
    char b[32];
    std::strftime(b, sizeof b, "%Y-%m-%d", std::localtime(&t));
    return b;
}

std::string driver_version(const rt::DeviceInfo& d) {
    const uint32_t v = d.driver_version;
    char b[48];
    if (d.vendor_id == 0x10DE)  // NVIDIA packs 10.8.8.6 bits
        std::snprintf(b, sizeof b, "%u.%u.%u", v >> 22, (v >> 14) & 0xFF, (v >> 6) & 0xFF);
    else
        std::snprintf(b, sizeof b, "%u.%u.%u", VK_API_VERSION_MAJOR(v), VK_API_VERSION_MINOR(v), VK_API_VERSION_PATCH(v));
    return b;
}

json device_json(const rt::DeviceInfo& d) {
    return {{"name", d.name}, {"type", rt::device_type_name(d.type)}, {"vendor_id", d.vendor_id},
            {"driver_version", driver_version(d)},
            {"api_version", std::to_string(VK_API_VERSION_MAJOR(d.api_version)) + "." +
                                std::to_string(VK_API_VERSION_MINOR(d.api_version)) + "." +
                                std::to_string(VK_API_VERSION_PATCH(d.api_version))},
            {"subgroup_size", d.subgroup_size}, {"max_shared_memory", d.max_shared_memory},
            {"max_invocations", d.max_invocations}, {"device_local_bytes", d.device_local_bytes},
            {"host_vector_registers", d.host_vector_registers}};
}

double med(const json& s) { return s.is_object() ? s["median"].get<double>() : 0.0; }

json ratios(const json& gpu, const json& cpu) {
    json r = json::object();
    auto put = [&](const std::string& k, double c, double g) {
        if (c > 0 && g > 0) r[k] = c / g;
    };
    put("end_to_end", med(cpu["end_to_end_ms"]), med(gpu["end_to_end_ms"]));
    put("cached_touch", med(cpu["cached_touch_ms"]), med(gpu["cached_touch_ms"]));
    for (auto& [k, v] : gpu["stages_ms"].items())
        if (cpu["stages_ms"].contains(k)) put("stage " + k, med(cpu["stages_ms"][k]), med(v));
    // The reference's retrieval node against what retrieval adds to the GPU's ILU dispatch.
    if (gpu.contains("retrieval_split") && cpu.contains("retrieval_split"))
        put("retrieval in the ILU", cpu["retrieval_split"]["node_ms"].get<double>(),
            gpu["retrieval_split"]["epilogue_ms"].get<double>());
    return r;
}

// The GPU measurement, with the peak probe around it when --probe asks.
void measure_gpu(json& report, const Args& a, const WeightStore& weights, const ModelConfig& cfg,
                 bench::ModelBenchInputs& in, rt::Context& ctx) {
    report["device"] = device_json(ctx.info());
    if (a.probe) {
        const double before = bench::peak_gflops(ctx);
        report["probe"] = {{"before", before}, {"dispatch_overhead_us", bench::dispatch_overhead_us(ctx)}};
    }
    VtlocRunner runner(weights, cfg, &ctx);
    in.probe_gflops = a.probe ? report["probe"]["before"].get<double>() : 0.0;
    report["gpu"] = bench::measure_model(runner, in, a.opt);
    if (cfg.head == Head::Ilu && cfg.ilu_iters > 0)
        report["gpu"]["ilu_variants"] = bench::ilu_variants(ctx, weights, cfg.ilu_iters, a.opt.reps);
    if (!a.opt.points.empty() && ctx.info().type != VK_PHYSICAL_DEVICE_TYPE_CPU)  // lavapipe's rule was measured
        report["gpu"]["fps_variants"] = bench::fps_variants(ctx, a.opt.reps);
    if (a.probe) {  // the higher of before/after: a busy machine cannot flatter the fractions
        const double after = bench::peak_gflops(ctx);
        report["probe"]["after"] = after;
        const double peak = std::max(in.probe_gflops, after);
        report["probe"]["gflops"] = peak;
        bench::set_fractions_of_peak(report["gpu"]["efficiency"]["conv"], peak);
        bench::set_fractions_of_peak(report["gpu"]["efficiency"]["mlp"], peak);
        if (report["gpu"].contains("points"))
            for (json& row : report["gpu"]["points"]) bench::set_fractions_of_peak(row["mlp"], peak);
    }
}

void measure_cpu(json& report, const Args& a, const WeightStore& weights, const ModelConfig& cfg,
                 bench::ModelBenchInputs& in) {
    bench::ModelBenchOptions c = a.opt;
    c.reps = a.cpu_reps;
    c.warmup = 0;  // nothing to compile or upload
    c.profile_reps = 1;
    c.stepped_iters = 0;  // per-iteration node times come from the sweep's ILU node
    VtlocRunner runner(weights, cfg, nullptr);
    in.probe_gflops = 0;  // the probe measures the GPU, not this
    report["cpu"] = bench::measure_model(runner, in, c);
    if (report.contains("gpu")) report["cpu_over_gpu"] = ratios(report["gpu"], report["cpu"]);
}

// The report, then --json and --plot.
void write_report(const json& report, const Args& a) {
    bench::print_report(report, stdout);
    if (!a.json_path.empty()) {
        std::ofstream f(a.json_path);
        if (!(f << report.dump(2) << "\n")) throw Error("cannot write " + a.json_path);
        std::printf("\nJSON: %s\n", a.json_path.c_str());
    }
    if (!a.plot_path.empty()) {
        bench::draw_plot(report, a.plot_path);
        std::printf("plot: %s\n", a.plot_path.c_str());
    }
}

int run(int argc, char** argv) {
    Args a = parse(argc, argv);
    std::string weights_path = !a.weights.empty() ? a.weights
                               : !a.config.empty() ? random_export(a.config)
                                                   : (data_dir() / kDefaultModel).string();
    const std::string image_path = !a.image.empty() ? a.image : (data_dir() / "examples" / "touch_01.png").string();
    const std::string object_path = !a.object.empty() ? a.object : (data_dir() / "examples" / "mug.glb").string();

    WeightStore weights = WeightStore::load(weights_path);
    const ModelConfig cfg = config_of(weights);
    const int64_t n_points = cfg.point.n_points;
    io::RgbImage img = io::load_tactile_image(image_path);
    HostTensor cloud = io::load_object(object_path, n_points);
    io::require_points(cloud, n_points, object_path);
    const std::string ext = fs::path(object_path).extension().string();
    if (ext != ".glb" && ext != ".gltf" && !a.opt.points.empty()) {
        std::fprintf(stderr, "note: --points needs a mesh to sample; %s is a point file, skipping the point sweep\n",
                     object_path.c_str());
        a.opt.points.clear();
    }

    json report;
    report["schema"] = "vtloc-bench/1";
    report["date"] = today();
    const size_t params = weights.parameter_count();
    report["model"] = {{"source", weights_path}, {"config_name", cfg.name},
                       {"parameters", params}, {"mib_fp32", double(params) * 4 / (1024.0 * 1024.0)},
                       {"file_bytes", fs::file_size(weights_path)}};
    report["inputs"] = {{"image", image_path}, {"image_size", {img.height, img.width}}, {"object", object_path},
                        {"points", cloud.shape[0]}, {"candidates", "the object cloud's points"}};
    report["settings"] = {{"reps", a.opt.reps}, {"warmup", a.opt.warmup}, {"profile_reps", a.opt.profile_reps},
                          {"cpu_reps", a.cpu_reps}, {"iters", a.opt.iters}, {"stepped", a.opt.stepped_iters},
                          {"batch", a.opt.batches}, {"points", a.opt.points}, {"backend", a.backend}};

    bench::ModelBenchInputs in;
    in.image = ops::tactile_image_tensor(img.pixels.data(), img.height, img.width);
    if (!a.plan_for.empty()) {
        rt::ContextOptions co;
        co.plan_for = rt::read_device_profile(a.plan_for);
        rt::Context plan_ctx(co);
        report["plan"] = bench::plan_model(plan_ctx, weights, cfg, in.image, cloud);
        bench::check_validation(plan_ctx, "vtloc-bench --plan-for");
        bench::print_plan(report["plan"], stdout);
        if (!a.json_path.empty()) {
            std::ofstream f(a.json_path);
            if (!(f << report.dump(2) << "\n")) throw Error("cannot write " + a.json_path);
        }
        return 0;
    }
    in.cloud = cloud;
    in.object = object_path;

    report["device"] = {{"name", "CPU reference (one thread)"}, {"type", "cpu"}, {"driver_version", "-"},
                        {"subgroup_size", 0}};
    report["host"] = bench::host_cpu();
    std::unique_ptr<rt::Context> ctx;
    if (a.backend != "cpu") {
        ctx = std::make_unique<rt::Context>();
        measure_gpu(report, a, weights, cfg, in, *ctx);
    }
    if (a.backend != "gpu") measure_cpu(report, a, weights, cfg, in);

    if (a.vs_pytorch) {
        bench::TorchRun t{python_interpreter(VTLOC_PYTHON), data_dir().string(), fs::absolute(weights_path).string(),
                          fs::absolute(image_path).string(), cloud, a.opt.reps, a.opt.warmup, a.torch_device};
        report["pytorch"] = bench::run_pytorch(t);
        report["engine_over_pytorch"] = bench::engine_over_pytorch(report.contains("gpu") ? report["gpu"] : report["cpu"],
                                                                   report["pytorch"]);
    }

    if (a.tracker) {
        bench::TrackerBenchOptions t;
        t.tour = !a.tracker_tour.empty() ? a.tracker_tour : (data_dir() / "examples" / "potato_tour.json").string();
        t.touches = a.tracker_touches, t.window = a.tracker_window, t.cycle = a.tracker_cycle;
        json& tr = report["tracker"];
        if (ctx) {
            t.reps = a.opt.reps;
            tr["gpu"] = bench::measure_tracker(ctx.get(), t);
        }
        t.reps = a.cpu_reps;  // the CPU reference always runs: the stage reports the two side by side
        tr["cpu"] = bench::measure_tracker(nullptr, t);
        if (tr.contains("gpu") && med(tr["gpu"]["touch_ms"]) > 0)
            tr["cpu_over_gpu"] = med(tr["cpu"]["touch_ms"]) / med(tr["gpu"]["touch_ms"]);
    }

    if (a.gel) {
        bench::GelBenchOptions g;
        const std::string tour = !a.tracker_tour.empty() ? a.tracker_tour : (data_dir() / "examples" / "potato_tour.json").string();
        g.object = io::read_touch_sequence(tour).object;
        g.reps = ctx ? a.opt.reps : a.cpu_reps;
        report["gel"] = bench::measure_gel(ctx.get(), g);
    }

    if (ctx) {  // with VTLOC_VALIDATION=1 (the smoke test), a validation message fails the run
        bench::check_validation(*ctx, "vtloc-bench");
    }
    write_report(report, a);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vtloc-bench: %s\n", e.what());
        return 1;
    }
}
