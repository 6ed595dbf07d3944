#pragma once
// vtloc-bench's readable table and its plot, both drawn from the JSON report.
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

namespace vtloc::bench {

void print_report(const nlohmann::json& report, std::FILE* out);

// Latency over N (end to end and the ILU node) and the per-stage breakdown, as a PNG.
void draw_plot(const nlohmann::json& report, const std::string& path);

}  // namespace vtloc::bench
