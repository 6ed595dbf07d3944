#pragma once
// `vtloc check` results as JSON (the --json file).
#include <nlohmann/json.hpp>

#include "vtloc/vtloc.h"

namespace vtloc::cli {

nlohmann::json check_json(const api::CheckResult& r, const api::CheckOptions& o);
nlohmann::json ops_check_json(const api::OpsCheckResult& r);
nlohmann::json tracker_check_json(const api::TrackerCheckResult& r, const api::TrackerCheckOptions& o);

}  // namespace vtloc::cli
