#include "engine/weights.h"

#include "base/error.h"
#include "engine/safetensors.h"

namespace vtloc {

WeightStore WeightStore::load(const std::string& path) {
    return from_file(SafetensorsFile::load(path, "safetensors weight file"));
}

WeightStore WeightStore::from_file(const SafetensorsFile& file) {
    WeightStore w;
    w.source_ = file.source();
    auto it = file.metadata().find("vtloc.config");
    if (it == file.metadata().end())
        throw Error(file.source() + ": missing __metadata__[\"vtloc.config\"] (not a VTLoc weight file?)");
    try {
        w.config_ = nlohmann::json::parse(it->second);
    } catch (const nlohmann::json::exception& e) {
        throw Error(file.source() + ": __metadata__[\"vtloc.config\"] is not valid JSON (" + e.what() + ")");
    }
    if (!w.config_.is_object())
        throw Error(file.source() + ": __metadata__[\"vtloc.config\"] is not a JSON object");

    for (const TensorInfo& t : file.tensors()) {
        switch (t.dtype) {
            case DType::F32: case DType::F16: case DType::BF16:
                w.tensors_[t.name] = std::make_shared<const HostTensor>(t.shape, file.to_f32(t));
                break;
            case DType::I64:
                break;  // bookkeeping such as BatchNorm's num_batches_tracked
            default:
                throw Error(file.source() + ": tensor '" + t.name + "' has dtype " + dtype_name(t.dtype) +
                            "; weight tensors must be F32 or F16 (I64 is ignored)");
        }
    }
    return w;
}

void WeightStore::add(const std::string& name, HostTensor t) {
    if (int64_t(t.data.size()) != numel(t.shape))
        throw Error("weight '" + name + "': data size does not match shape " + shape_str(t.shape));
    tensors_[name] = std::make_shared<const HostTensor>(std::move(t));
}

const HostTensor& WeightStore::get(const std::string& name) const {
    auto it = tensors_.find(name);
    if (it == tensors_.end()) throw Error(source_ + ": weight '" + name + "' is missing");
    return *it->second;
}

const HostTensor& WeightStore::get(const std::string& name, const Shape& expected) const {
    const HostTensor& t = get(name);
    if (t.shape != expected)
        throw Error(source_ + ": weight '" + name + "' has shape " + shape_str(t.shape) + ", expected " +
                    shape_str(expected));
    return t;
}

std::vector<std::string> WeightStore::names() const {
    std::vector<std::string> out;
    for (auto& [k, v] : tensors_) out.push_back(k);
    return out;
}

size_t WeightStore::parameter_count() const {
    size_t n = 0;
    for (auto& [k, v] : tensors_) n += v->data.size();
    return n;
}

}  // namespace vtloc
