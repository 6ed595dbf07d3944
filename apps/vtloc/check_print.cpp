#include "apps/vtloc/check_print.h"

#include <cmath>
#include <cstdio>

#include "base/atomic_write.h"
#include "base/error.h"

namespace vtloc::cli {

std::string g3(double v) {
    if (std::isinf(v)) return "inf";
    char b[32];
    std::snprintf(b, sizeof b, "%.2e", v);
    return b;
}

std::string shapes_str(const std::vector<std::vector<int64_t>>& shapes) {
    std::string s;
    for (const auto& sh : shapes) {
        s += s.empty() ? "[" : " [";
        for (size_t i = 0; i < sh.size(); ++i) s += (i ? ", " : "") + std::to_string(sh[i]);
        s += "]";
    }
    return s;
}

void print_device(const api::CheckDevice& d, bool limits) {
    std::printf("device     %s (%s), Vulkan %s\n", d.name.c_str(), d.type.c_str(), d.vulkan.c_str());
    std::printf("driver     %s\n", d.driver.c_str());
    if (!limits) return;
    std::printf("limits     (what chooses workgroup sizes, tiles and texel / storage-buffer paths)\n");
    for (auto& [k, v] : d.limits) std::printf("  %-28s %s\n", k.c_str(), v.c_str());
}

void write_json(const std::string& path, const nlohmann::json& j) {
    try {
        write_file_atomic(path, j.dump(2) + "\n");
    } catch (const vtloc::Error& e) {
        throw api::Error(e.what());
    }
}

std::string indices_str(const api::CheckError& e) {
    return !e.has_indices ? "-" : e.indices_equal ? "equal" : "DIFFER";
}

void print_node(const api::NodeCheck& n) {
    std::printf("  node       %s (op %s)\n", n.node.c_str(), n.op.c_str());
    std::printf("  inputs     %s\n  outputs    %s\n", shapes_str(n.input_shapes).c_str(),
                shapes_str(n.output_shapes).c_str());
    for (const std::string& d : n.dispatches) std::printf("  dispatch   %s\n", d.c_str());
    if (n.dispatches.empty()) std::printf("  dispatch   (none: a buffer copy)\n");
    if (!n.failure.empty()) std::printf("  reference  threw: %s\n", n.failure.c_str());
    if (!n.error.first_mismatch.empty())
        std::printf("  mismatch   %s; %lld elements out of tolerance; max abs %s, max rel %s\n",
                    n.error.first_mismatch.c_str(), (long long)n.error.mismatches, g3(n.error.max_abs).c_str(),
                    g3(n.error.max_rel).c_str());
}

}  // namespace vtloc::cli
