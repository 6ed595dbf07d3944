#include "apps/vtloc/report.h"

#include <cstdio>

namespace vtloc::cli {

using nlohmann::json;

json point_json(const std::array<double, 3>& p) { return json::array({p[0], p[1], p[2]}); }

json model_json(const api::ModelInfo& m, bool random) {
    json j{{"path", m.path},           {"name", m.name},
           {"head", m.head},           {"parameters", m.parameter_count},
           {"size_mib", m.size_mib},   {"file_bytes", m.file_bytes},
           {"sample_points", m.sample_points}};
    if (random) j["note"] = "random weights: no trained model exists yet; predictions are meaningless";
    return j;
}

json object_json(const api::Object& o, const std::string& candidates_path) {
    return {{"path", o.source()},
            {"points", o.cloud().size()},
            {"candidates", o.candidate_count()},
            {"candidates_from", candidates_path.empty() ? "the object's points" : candidates_path},
            {"normals", o.normals_estimated() ? "estimated (k = 16 nearest points, PCA)" : "given"},
            {"centre", point_json(o.centre())},
            {"scale", o.scale()}};
}

json timings_json(const api::Timings& t) {
    json j{{"wall_ms", t.wall_ms}};
    if (!t.nodes.empty()) {
        j["gpu_ms"] = t.gpu_ms;
        json nodes = json::array();
        for (auto& [name, ms] : t.nodes) nodes.push_back({{"node", name}, {"ms", ms}});
        j["nodes"] = nodes;
    }
    return j;
}

json touch_json(const api::TouchResult& r) {
    json topk = json::array();
    for (size_t i = 0; i < r.topk_index.size(); ++i)
        topk.push_back({{"rank", i + 1},
                        {"index", r.topk_index[i]},
                        {"score", r.topk_score[i]},
                        {"point", point_json(r.topk_point[i])}});
    json iterates = json::array();
    for (auto& c : r.iterates) iterates.push_back(point_json(c));
    return {{"contact", point_json(r.contact)},
            {"contact_normalised", point_json(r.contact_normalised)},
            {"iterates", iterates},
            {"topk", topk},
            {"alignment", r.alignment ? json(*r.alignment) : json(nullptr)},
            {"timings_ms", timings_json(r.timings)}};
}

std::string count_str(uint64_t n) {
    std::string digits = std::to_string(n), out;
    for (size_t i = 0; i < digits.size(); ++i) {
        if (i && (digits.size() - i) % 3 == 0) out += ',';
        out += digits[i];
    }
    return out;
}

void print_model(const api::ModelInfo& m, bool random) {
    std::printf("model     %s: %s, %s head, %s parameters (%.2f MiB as fp32)\n", m.path.c_str(), m.name.c_str(),
                m.head.c_str(), count_str(m.parameter_count).c_str(), m.size_mib);
    if (random)
        std::printf("          NOTE: RANDOM WEIGHTS. No trained VTLoc model exists yet; this is an untrained\n"
                    "          export (models/README.md), so its predictions are meaningless.\n");
}

void print_device(const api::DeviceInfo& d, bool chosen) {
    std::printf("%s[%d] %s (%s, Vulkan %d.%d)\n", chosen ? "* " : "  ", d.index, d.name.c_str(), d.type.c_str(),
                d.api_major, d.api_minor);
    std::printf("      subgroup %u, shared memory %u KiB, workgroup <= %u invocations (%u x %u x %u),\n"
                "      storage binding <= %llu MiB, %u storage buffers per stage, push constants %u B,\n"
                "      texel buffer <= %u elements, device-local memory %llu MiB, timestamps %s\n",
                d.subgroup_size, d.shared_memory_bytes / 1024, d.max_workgroup_invocations, d.max_workgroup_size[0],
                d.max_workgroup_size[1], d.max_workgroup_size[2], (unsigned long long)(d.max_storage_buffer_bytes >> 20),
                d.max_storage_buffers, d.max_push_constant_bytes, d.max_texel_buffer_elements,
                (unsigned long long)(d.device_local_bytes >> 20), d.timestamps ? "yes" : "no");
    if (d.host_vector_registers > 0)  // a CPU device: its code runs on the host's vector registers
        std::printf("      host CPU vector registers %u\n", d.host_vector_registers);
    if (d.compute_units > 0) std::printf("      compute units %u\n", d.compute_units);
}

void print_touch(const api::TouchResult& r, const std::string& indent) {
    std::printf("%scontact   %s  (normalised %s)\n", indent.c_str(), point_str(r.contact).c_str(),
                point_str(r.contact_normalised, 3).c_str());
    for (size_t i = 0; i < r.topk_index.size(); ++i)
        std::printf("%s%s %zu. candidate %d at %s, score %.4g\n", indent.c_str(), i ? "         " : "top-K    ", i + 1,
                    r.topk_index[i], point_str(r.topk_point[i]).c_str(), double(r.topk_score[i]));
    if (r.alignment)
        std::printf("%salignment chamfer(P^d, P) = %.4g (GMA; lower = the pseudo-cloud fits the object better)\n",
                    indent.c_str(), double(*r.alignment));
}

void write_heatmap_option(const Args& a, const api::Object& object, const std::vector<float>& heat,
                          nlohmann::json& outputs) {
    if (auto p = a.get("--heatmap")) {
        api::write_heatmap_ply(*p, object, heat);
        outputs["heatmap"] = *p;
    }
}

}  // namespace vtloc::cli
