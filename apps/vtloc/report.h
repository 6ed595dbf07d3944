#pragma once
// Results as JSON and as text, shared by the touch commands.
#include <nlohmann/json.hpp>
#include <string>

#include "apps/vtloc/cli.h"

namespace vtloc::cli {

nlohmann::json point_json(const std::array<double, 3>& p);
nlohmann::json model_json(const api::ModelInfo& m, bool random);
nlohmann::json object_json(const api::Object& o, const std::string& candidates_path);
nlohmann::json touch_json(const api::TouchResult& r);
nlohmann::json timings_json(const api::Timings& t);

// 1234567 -> "1,234,567".
std::string count_str(uint64_t n);
// "model  path: name, ..." and the untrained-weights warning when it applies.
void print_model(const api::ModelInfo& m, bool random);
void print_device(const api::DeviceInfo& d, bool chosen);
// Contact, top-K and alignment of one touch, indented by `indent`.
void print_touch(const api::TouchResult& r, const std::string& indent = "");
// --heatmap FILE: the heat-map PLY over the object's cloud, its path recorded in `outputs`.
void write_heatmap_option(const Args& a, const api::Object& object, const std::vector<float>& heat,
                          nlohmann::json& outputs);

}  // namespace vtloc::cli
