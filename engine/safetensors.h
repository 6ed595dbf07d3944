#pragma once
// The safetensors format (SPEC section 7): u64 little-endian header length,
// a JSON header, then raw little-endian tensor data. The reader checks every
// structural rule and names the offending tensor or field in its errors.
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "engine/tensor.h"

namespace vtloc {

enum class DType { F64, F32, F16, BF16, I64, I32, I16, I8, U8, BOOL };

size_t dtype_size(DType t);
const char* dtype_name(DType t);
std::optional<DType> parse_dtype(const std::string& s);

struct TensorInfo {
    std::string name;
    DType dtype = DType::F32;
    Shape shape;
    uint64_t begin = 0, end = 0;  // byte offsets into the data area
};

class SafetensorsFile {
public:
    static constexpr uint64_t kMaxHeaderBytes = 100ull * 1000 * 1000;

    // `kind` says what the file should be ("calibration file"): bytes that are not safetensors
    // at all then add "(not a <kind>?)" to the error; a file that cannot be opened does not.
    static SafetensorsFile load(const std::string& path, const std::string& kind = "");
    // `source` names the data in error messages (usually the path).
    static SafetensorsFile parse(std::vector<uint8_t> bytes, const std::string& source, const std::string& kind = "");

    const std::string& source() const { return source_; }
    const std::vector<TensorInfo>& tensors() const { return tensors_; }  // ordered by offset
    const TensorInfo* find(const std::string& name) const;
    const TensorInfo& at(const std::string& name) const;  // throws if absent
    const std::map<std::string, std::string>& metadata() const { return metadata_; }

    std::span<const uint8_t> bytes(const TensorInfo& t) const;
    // F32, F16 and BF16 widened to float; anything else throws.
    std::vector<float> to_f32(const TensorInfo& t) const;
    // Integer dtypes narrowed to int32 (values outside int32 throw).
    std::vector<int32_t> to_i32(const TensorInfo& t) const;

private:
    static SafetensorsFile parse_tensors(std::vector<uint8_t> bytes, const std::string& source);
    std::string source_;
    std::vector<uint8_t> file_;
    uint64_t data_start_ = 0;
    std::vector<TensorInfo> tensors_;
    std::map<std::string, std::string> metadata_;
};

float half_to_float(uint16_t h);

// One tensor to write: raw little-endian bytes of numel(shape) * dtype_size.
struct TensorBlob {
    std::string name;
    DType dtype = DType::F32;
    Shape shape;
    std::vector<uint8_t> bytes;

    static TensorBlob f32(std::string name, Shape shape, const std::vector<float>& v);
    static TensorBlob i32(std::string name, Shape shape, const std::vector<int32_t>& v);
};

// Writes tensors contiguously in the given order; header padded to 8 bytes.
void write_safetensors(const std::string& path, const std::vector<TensorBlob>& tensors,
                       const std::map<std::string, std::string>& metadata);

}  // namespace vtloc
