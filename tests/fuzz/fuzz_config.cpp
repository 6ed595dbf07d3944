// The model config parser on arbitrary JSON text.
#include <nlohmann/json.hpp>

#include "base/error.h"
#include "engine/model/model_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const nlohmann::json j = nlohmann::json::parse(data, data + size, nullptr, false);
    if (j.is_discarded()) return 0;
    try {
        vtloc::ModelConfig::parse(j, "fuzz");
    } catch (const vtloc::Error&) {
    }
    return 0;
}
