// vtloc info (a weight file) and vtloc devices (Vulkan devices).
#include <cstdio>
#include <fstream>

#include "apps/vtloc/report.h"

namespace vtloc::cli {

namespace {

// The paper's own figure, for comparison with the config of the same name.
constexpr double kPaperMiB = 124.28;

std::string shape_text(const std::vector<int64_t>& s) {
    std::string out = "[";
    for (size_t i = 0; i < s.size(); ++i) out += (i ? ", " : "") + std::to_string(s[i]);
    return out + "]";
}

}  // namespace

int cmd_info(Session&, int argc, char** argv) {
    Args a(argc, argv, 2, {{"--json", false}}, 1);
    if (a.help()) {
        std::puts("usage: vtloc info [M] [--json]\n"
                  "\n"
                  "Checks a weight file (default: the shipped model) and prints its config, parameter\n"
                  "count, size and tensor list. No GPU is used.\n"
                  "\n"
                  "  --json    print it all as JSON");
        return 0;
    }
    const std::string path = a.positional().empty() ? default_model_path() : a.positional()[0];
    api::ModelInfo m = api::inspect_model(path);
    const bool random = is_shipped_random_model(path);
    if (a.flag("--json")) {
        nlohmann::json j = model_json(m, random);
        j["config"] = nlohmann::json::parse(m.config_json);
        j["paper_size_mib"] = kPaperMiB;
        nlohmann::json tensors = nlohmann::json::array();
        for (const api::TensorSummary& t : m.tensors)
            tensors.push_back({{"name", t.name}, {"dtype", t.dtype}, {"shape", t.shape}});
        j["tensors"] = tensors;
        std::printf("%s\n", j.dump(2).c_str());
        return 0;
    }
    std::printf("file        %s (%.2f MiB on disk)\n", m.path.c_str(), double(m.file_bytes) / (1024.0 * 1024.0));
    std::printf("config      %s: C = %lld, K = %lld, %s head%s, normals %s, GMA %s\n", m.name.c_str(),
                (long long)m.feature_size, (long long)m.default_k, m.head.c_str(),
                m.head == "ilu" ? (" (" + std::to_string(m.default_iters) + " iterations)").c_str() : "",
                m.use_normals ? "on" : "off", m.has_gma ? "on" : "off");
    std::printf("tactile     centre crop %lld, input %lld x %lld\n", (long long)m.crop, (long long)m.input_size,
                (long long)m.input_size);
    std::printf("points      %lld sampled from a mesh; at least %lld needed\n", (long long)m.sample_points,
                (long long)m.min_points);
    if (m.sensor)
        std::printf("sensor      %g mm per pixel, %d x %d frames (other pixel sizes: --mm-per-px)\n",
                    m.sensor->mm_per_px, m.sensor->width, m.sensor->height);
    else
        std::printf("sensor      not recorded (frames are used as given)\n");
    std::printf("parameters  %s (weights and BatchNorm statistics) = %.2f MiB as fp32\n",
                count_str(m.parameter_count).c_str(), m.size_mib);
    std::printf("            (the paper reports %.2f MiB for its VTLoc model)\n", kPaperMiB);
    if (random) std::printf("NOTE        RANDOM WEIGHTS: an untrained export (models/README.md)\n");
    std::printf("config JSON\n%s\n", m.config_json.c_str());
    std::printf("tensors (%zu)\n", m.tensors.size());
    for (const api::TensorSummary& t : m.tensors)
        std::printf("  %-52s %-4s %s\n", t.name.c_str(), t.dtype.c_str(), shape_text(t.shape).c_str());
    return 0;
}

int cmd_devices(Session& s, int argc, char** argv) {
    Args a(argc, argv, 2, {{"--json", false}, {"--save-profile", true}});
    if (a.help()) {
        std::puts("usage: vtloc devices [--json] [--save-profile FILE]\n"
                  "\n"
                  "Lists the Vulkan devices with compute and the limits the engine uses; '*' marks the\n"
                  "one it picks (VTLOC_DEVICE=<index|name> chooses another). --save-profile writes that\n"
                  "device's limits as a device profile: `vtloc-bench --plan-for FILE` then shows, on any\n"
                  "machine, the dispatches the engine would give it.");
        return 0;
    }
    std::vector<api::DeviceInfo> devices = api::list_devices();
    const int chosen = s.gpu().device().index;
    if (auto path = a.get("--save-profile")) {
        std::ofstream f(*path, std::ios::binary);
        if (!(f << api::device_profile(chosen)) || !(f.close(), f))
            throw api::Error(*path + ": cannot write the device profile there");
        std::printf("wrote %s (device %d)\n", path->c_str(), chosen);
        return 0;
    }
    if (a.flag("--json")) {
        nlohmann::json out = nlohmann::json::array();
        for (const api::DeviceInfo& d : devices)
            out.push_back({{"index", d.index},
                           {"name", d.name},
                           {"type", d.type},
                           {"chosen", d.index == chosen},
                           {"vulkan", std::to_string(d.api_major) + "." + std::to_string(d.api_minor)},
                           {"subgroup_size", d.subgroup_size},
                           {"shared_memory_bytes", d.shared_memory_bytes},
                           {"max_workgroup_invocations", d.max_workgroup_invocations},
                           {"max_workgroup_size", d.max_workgroup_size},
                           {"max_workgroup_count", d.max_workgroup_count},
                           {"max_storage_buffer_bytes", d.max_storage_buffer_bytes},
                           {"max_storage_buffers", d.max_storage_buffers},
                           {"max_push_constant_bytes", d.max_push_constant_bytes},
                           {"max_texel_buffer_elements", d.max_texel_buffer_elements},
                           {"timestamps", d.timestamps},
                           {"device_local_bytes", d.device_local_bytes},
                           {"host_vector_registers", d.host_vector_registers},
                           {"compute_units", d.compute_units}});
        std::printf("%s\n", out.dump(2).c_str());
        return 0;
    }
    for (const api::DeviceInfo& d : devices) print_device(d, d.index == chosen);
    return 0;
}

}  // namespace vtloc::cli
