// The safetensors reader (header JSON, offsets, dtypes, data) and, when the file
// carries a config, the typed config parser and the weight checks behind it.
#include <cstdint>
#include <vector>

#include "base/error.h"
#include "engine/model/model_config.h"
#include "engine/safetensors.h"
#include "engine/weights.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    try {
        vtloc::SafetensorsFile f = vtloc::SafetensorsFile::parse(std::vector<uint8_t>(data, data + size), "fuzz");
        vtloc::WeightStore w = vtloc::WeightStore::from_file(f);
        vtloc::ModelConfig::parse(w.config(), "fuzz");
    } catch (const vtloc::Error&) {
    }
    return 0;
}
