#include "bench/versus.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>
#include <unistd.h>

#include "base/error.h"
#include "engine/io/ply.h"

namespace vtloc::bench {

using nlohmann::json;

json host_cpu() {
    std::ifstream f("/proc/cpuinfo");
    std::string line, model = "unknown";
    std::set<std::string> flags;
    const std::set<std::string> wanted{"avx", "avx2", "fma", "avx512f", "avx512bw", "avx512vl", "avx512_vnni", "asimd", "neon"};
    while (std::getline(f, line)) {
        const size_t colon = line.find(':');
        if (colon == std::string::npos) continue;
        std::string key = line.substr(0, colon);
        while (!key.empty() && (key.back() == ' ' || key.back() == '\t')) key.pop_back();
        const std::string value = colon + 2 <= line.size() ? line.substr(colon + 2) : "";
        if ((key == "model name" || key == "Model") && model == "unknown") model = value;
        if (key == "flags" || key == "Features") {
            std::istringstream ss(value);
            for (std::string w; ss >> w;)
                if (wanted.count(w)) flags.insert(w);
        }
    }
    json host{{"cpu", model}, {"cores", std::thread::hardware_concurrency()},
              {"simd", std::vector<std::string>(flags.begin(), flags.end())}};
    // Mesa's JIT held below the CPU (bench/README.md, "Measuring the AVX2 code
    // paths"): the flags above are the CPU's, not what lavapipe's code uses.
    for (const char* v : {"GALLIUM_OVERRIDE_CPU_CAPS", "GALLIUM_NOSSE"})
        if (const char* s = std::getenv(v)) host["jit_override"][v] = s;
    return host;
}

json run_pytorch(const TorchRun& t) {
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("vtloc-bench-torch-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const fs::path cloud = dir / "cloud.ply", out = dir / "torch.json";
    io::write_ply(cloud.string(), t.cloud);
    const std::string cmd = "cd '" + t.repo + "' && PYTHONDONTWRITEBYTECODE=1 '" + t.python +
                            "' -m weights_tools.bench_torch --weights '" + t.weights + "' --tactile '" + t.image +
                            "' --cloud '" + cloud.string() + "' --reps " + std::to_string(t.reps) + " --warmup " +
                            std::to_string(t.warmup) + " --device " + t.device + " --json '" + out.string() + "' >&2";
    std::fprintf(stderr, "PyTorch reference: %s\n", cmd.c_str());
    const int rc = std::system(cmd.c_str());
    std::ifstream f(out);
    json j = json::parse(f, nullptr, false);
    std::error_code ec;
    fs::remove_all(dir, ec);
    if (rc != 0 || j.is_discarded())
        throw Error("--vs-pytorch: the PyTorch reference failed (weights_tools needs python3 with torch; "
                    "VTLOC_PYTHON picks the interpreter)");
    return j;
}

json engine_over_pytorch(const json& e, const json& t) {
    json r = json::object();
    auto med = [](const json& s) { return s.is_object() && s.contains("median") ? s["median"].get<double>() : 0.0; };
    auto put = [&](const std::string& k, double engine, double torch) {
        if (engine > 0 && torch > 0) r[k] = engine / torch;
    };
    put("end_to_end", med(e["end_to_end_ms"]), med(t["end_to_end_ms"]));
    // The two sides run one after the other, and on a shared host a busy phase can
    // fall on either: the fastest runs are the undisturbed estimates (load only
    // ever slows a run down), so their ratio is the one noise cannot move far.
    auto fastest = [](const json& s) { return s.is_object() && s.contains("min") ? s["min"].get<double>() : 0.0; };
    put("end_to_end_fastest", fastest(e["end_to_end_ms"]), fastest(t["end_to_end_ms"]));
    const json& es = e["stages_ms"];
    const json& ts = t["stages_ms"];
    for (const char* s : {"preprocess", "tactile", "point", "retrieval"})
        if (es.contains(s)) put(std::string("stage ") + s, med(es[s]), med(ts[s]));
    // Where retrieval runs in the ILU's dispatch, its share of the head node is
    // what it adds there (model_bench.cpp retrieval_split).
    double epilogue = 0.0;
    if (!es.contains("retrieval") && e.contains("retrieval_split")) {
        // Noise can make the difference <= 0: then neither ratio takes it. It comes
        // from other runs than the head's median (one each in a smoke test), so a
        // busy moment can also make it exceed that median: at most the whole head.
        const double head = es.contains("head") ? med(es["head"]) : 0.0;
        epilogue = std::clamp(e["retrieval_split"]["epilogue_ms"].get<double>(), 0.0, head);
        put("stage retrieval", epilogue, med(ts["retrieval"]));
    }
    // The reference's "heads" is GMA and the contact head together.
    const double heads =
        (es.contains("gma") ? med(es["gma"]) : 0.0) + (es.contains("head") ? med(es["head"]) - epilogue : 0.0);
    put("stage gma + head", heads, med(ts["heads"]));
    return r;
}

}  // namespace vtloc::bench
