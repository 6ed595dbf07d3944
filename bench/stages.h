#pragma once
// The stages vtloc-bench reports, from a node's op and name (the names
// engine/model gives): preprocess, tactile encoder, point encoder, GMA, the
// contact head (ILU or MCR) and retrieval + heat-map.
#include <string>
#include <vector>

namespace vtloc::bench {

const std::vector<std::string>& stage_names();
// One of stage_names(), or "other" for a node no stage claims.
std::string stage_of(const std::string& op, const std::string& node_name);

}  // namespace vtloc::bench
