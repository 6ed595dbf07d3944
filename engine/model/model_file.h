#pragma once
// A weight file opened for inference: its tensors, its typed config, and the
// proof that every tensor the network reads is there with the config's shape,
// so a wrong file fails at load with one message, not at the first touch.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/model/model_config.h"
#include "engine/model/prepared_weights.h"
#include "engine/tensor.h"
#include "engine/weights.h"

namespace vtloc {

struct ModelFile {
    struct Tensor {
        std::string name, dtype;
        Shape shape;
        bool floating = false;  // F32/F16/BF16 (parameters), not integer counters
    };
    PreparedWeights weights;  // prepare_weights' set: what the network reads
    ModelConfig config;
    std::vector<Tensor> tensors;  // as stored in the file
    uint64_t file_bytes = 0;
};

// Throws vtloc::Error "<path>: <problem>".
ModelFile load_model_file(const std::string& path);

}  // namespace vtloc
