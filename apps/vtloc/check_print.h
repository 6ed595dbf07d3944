#pragma once
// What `vtloc check`'s forms print alike: numbers, shapes, the device, a node that failed.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "vtloc/vtloc.h"

namespace vtloc::cli {

std::string g3(double v);  // "1.23e-04"; "inf"
std::string shapes_str(const std::vector<std::vector<int64_t>>& shapes);
void print_device(const api::CheckDevice& d, bool limits);
void write_json(const std::string& path, const nlohmann::json& j);
std::string indices_str(const api::CheckError& e);  // "-", "equal" or "DIFFER"
void print_node(const api::NodeCheck& n);

}  // namespace vtloc::cli
