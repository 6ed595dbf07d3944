#pragma once
// Named fp32 weights plus the model config, read from a safetensors file
// (F32 kept, F16/BF16 widened on load, I64 such as num_batches_tracked ignored).
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "engine/tensor.h"

namespace vtloc {

class SafetensorsFile;

class WeightStore {
public:
    WeightStore() = default;
    static WeightStore load(const std::string& path);
    // Requires __metadata__["vtloc.config"] to be a JSON object.
    static WeightStore from_file(const SafetensorsFile& file);

    void add(const std::string& name, HostTensor t);
    void set_config(nlohmann::json c) { config_ = std::move(c); }

    bool has(const std::string& name) const { return tensors_.count(name) != 0; }
    // Throws naming the tensor when it is missing or its shape differs.
    const HostTensor& get(const std::string& name, const Shape& expected) const;
    const HostTensor& get(const std::string& name) const;

    const nlohmann::json& config() const { return config_; }
    const std::string& source() const { return source_; }
    std::vector<std::string> names() const;
    size_t parameter_count() const;
    uint64_t bytes() const { return 4 * uint64_t(parameter_count()); }  // the tensors' data

private:
    std::string source_ = "weights";
    // Read-only once added: a copy of the store shares them (a tracker made by with_options
    // shares its object's tables).
    std::map<std::string, std::shared_ptr<const HostTensor>> tensors_;
    nlohmann::json config_ = nlohmann::json::object();
};

}  // namespace vtloc
