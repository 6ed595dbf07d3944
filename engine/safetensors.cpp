#include "engine/safetensors.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "base/atomic_write.h"
#include "base/error.h"

static_assert(std::endian::native == std::endian::little, "safetensors I/O assumes a little-endian host");

namespace vtloc {

namespace {
struct DTypeRow { DType t; const char* name; size_t size; };
constexpr DTypeRow kDTypes[] = {
    {DType::F64, "F64", 8}, {DType::F32, "F32", 4}, {DType::F16, "F16", 2},
    {DType::BF16, "BF16", 2}, {DType::I64, "I64", 8}, {DType::I32, "I32", 4},
    {DType::I16, "I16", 2}, {DType::I8, "I8", 1}, {DType::U8, "U8", 1},
    {DType::BOOL, "BOOL", 1},
};
}  // namespace

size_t dtype_size(DType t) {
    for (auto& r : kDTypes) if (r.t == t) return r.size;
    return 0;
}
const char* dtype_name(DType t) {
    for (auto& r : kDTypes) if (r.t == t) return r.name;
    return "?";
}
std::optional<DType> parse_dtype(const std::string& s) {
    for (auto& r : kDTypes) if (s == r.name) return r.t;
    return std::nullopt;
}

float half_to_float(uint16_t h) {
    uint32_t sign = uint32_t(h & 0x8000) << 16;
    uint32_t exp = (h >> 10) & 0x1f;
    uint32_t man = h & 0x3ff;
    uint32_t bits;
    if (exp == 0) {
        if (man == 0) {
            bits = sign;
        } else {  // subnormal: renormalise
            int e = -1;
            do { ++e; man <<= 1; } while (!(man & 0x400));
            bits = sign | uint32_t(127 - 15 - e) << 23 | (man & 0x3ff) << 13;
        }
    } else if (exp == 31) {
        bits = sign | 0x7f800000u | man << 13;
    } else {
        bits = sign | (exp + 127 - 15) << 23 | man << 13;
    }
    return std::bit_cast<float>(bits);
}

SafetensorsFile SafetensorsFile::load(const std::string& path, const std::string& kind) {
    // A directory opens and reports a size on some libstdc++s (a huge one: bad_alloc, "out of memory").
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw Error(path + ": is a directory, not a " + (kind.empty() ? "safetensors file" : kind));
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) throw Error(path + ": cannot open file");
    std::streamsize size = in.tellg();
    if (size < 0) throw Error(path + ": cannot read file size");
    std::vector<uint8_t> bytes(static_cast<size_t>(size));
    in.seekg(0);
    if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), size))
        throw Error(path + ": read failed");
    return parse(std::move(bytes), path, kind);
}

namespace {

// One tensor's header entry, checked against the data area's size.
TensorInfo tensor_entry(const std::string& source, const std::string& name, const nlohmann::json& val,
                        uint64_t data_size) {
    auto tfail = [&](const std::string& msg) { return Error(source + ": tensor '" + name + "': " + msg); };
    if (!val.is_object()) throw tfail("entry is not a JSON object");
    if (!val.contains("dtype") || !val["dtype"].is_string()) throw tfail("missing or non-string dtype");
    if (!val.contains("shape") || !val["shape"].is_array()) throw tfail("missing or non-array shape");
    if (!val.contains("data_offsets") || !val["data_offsets"].is_array() || val["data_offsets"].size() != 2)
        throw tfail("data_offsets must be an array of two integers");
    TensorInfo t;
    t.name = name;
    std::string dt = val["dtype"].get<std::string>();
    auto parsed = parse_dtype(dt);
    if (!parsed) throw tfail("unknown dtype '" + dt + "'");
    t.dtype = *parsed;
    uint64_t count = 1;
    for (auto& d : val["shape"]) {
        if (!d.is_number_unsigned() && !(d.is_number_integer() && d.get<int64_t>() >= 0))
            throw tfail("shape entries must be non-negative integers");
        uint64_t v = d.get<uint64_t>();
        if (v != 0 && count > std::numeric_limits<uint64_t>::max() / 16 / v)
            throw tfail("shape is too large");
        count *= v;
        t.shape.push_back(int64_t(v));
    }
    for (auto& o : val["data_offsets"])
        if (!o.is_number_unsigned() && !(o.is_number_integer() && o.get<int64_t>() >= 0))
            throw tfail("data_offsets must be non-negative integers");
    t.begin = val["data_offsets"][0].get<uint64_t>();
    t.end = val["data_offsets"][1].get<uint64_t>();
    if (t.end < t.begin) throw tfail("data_offsets end before they begin");
    uint64_t need = count * dtype_size(t.dtype);
    if (need != t.end - t.begin)
        throw tfail("shape " + shape_str(t.shape) + " of " + dt + " needs " + std::to_string(need) +
                    " bytes but data_offsets span " + std::to_string(t.end - t.begin));
    if (t.end > data_size)
        throw tfail("data_offsets [" + std::to_string(t.begin) + ", " + std::to_string(t.end) +
                    "] run past the end of the data area (" + std::to_string(data_size) + " bytes)");
    return t;
}

// The tensors, sorted by offset, must tile the data area: no overlap, no gap, nothing after.
void check_tiling(const std::string& source, const std::vector<TensorInfo>& tensors, uint64_t data_size) {
    auto fail = [&](const std::string& msg) { return Error(source + ": " + msg); };
    uint64_t cursor = 0;
    const TensorInfo* prev = nullptr;
    for (const TensorInfo& t : tensors) {
        if (t.begin < cursor)
            throw fail("tensors '" + prev->name + "' and '" + t.name + "' overlap");
        if (t.begin > cursor)
            throw fail("gap of " + std::to_string(t.begin - cursor) + " bytes before tensor '" + t.name + "'");
        cursor = t.end;
        if (t.end > t.begin) prev = &t;
    }
    if (cursor != data_size)
        throw fail(std::to_string(data_size - cursor) +
                   " bytes after the last tensor are not covered by any tensor");
}

}  // namespace

SafetensorsFile SafetensorsFile::parse(std::vector<uint8_t> bytes, const std::string& source, const std::string& kind) {
    if (kind.empty()) return parse_tensors(std::move(bytes), source);
    try {
        return parse_tensors(std::move(bytes), source);
    } catch (const Error& e) {
        throw Error(std::string(e.what()) + " (not a " + kind + "?)");
    }
}

SafetensorsFile SafetensorsFile::parse_tensors(std::vector<uint8_t> bytes, const std::string& source) {
    auto fail = [&](const std::string& msg) { return Error(source + ": " + msg); };
    SafetensorsFile f;
    f.source_ = source;
    if (bytes.size() < 8)
        throw fail("file is " + std::to_string(bytes.size()) +
                   " bytes, too short to hold the 8-byte header length");
    uint64_t header_len;
    std::memcpy(&header_len, bytes.data(), 8);
    if (header_len > kMaxHeaderBytes)
        throw fail("header length " + std::to_string(header_len) + " exceeds the 100 MB limit");
    if (header_len > bytes.size() - 8)
        throw fail("header length " + std::to_string(header_len) + " runs past the end of the file (" +
                   std::to_string(bytes.size()) + " bytes)");

    nlohmann::json header;
    try {
        header = nlohmann::json::parse(bytes.begin() + 8, bytes.begin() + 8 + std::ptrdiff_t(header_len));
    } catch (const nlohmann::json::exception& e) {
        throw fail(std::string("header is not valid JSON (") + e.what() + ")");
    }
    if (!header.is_object()) throw fail("header is not a JSON object");

    f.data_start_ = 8 + header_len;
    const uint64_t data_size = bytes.size() - f.data_start_;
    for (auto& [key, val] : header.items()) {
        if (key == "__metadata__") {
            if (!val.is_object()) throw fail("__metadata__ is not a JSON object");
            for (auto& [mk, mv] : val.items()) {
                if (!mv.is_string()) throw fail("__metadata__[\"" + mk + "\"] is not a string");
                f.metadata_[mk] = mv.get<std::string>();
            }
            continue;
        }
        f.tensors_.push_back(tensor_entry(source, key, val, data_size));
    }

    std::sort(f.tensors_.begin(), f.tensors_.end(), [](const TensorInfo& a, const TensorInfo& b) {
        return a.begin != b.begin ? a.begin < b.begin : a.end < b.end;
    });
    check_tiling(source, f.tensors_, data_size);
    f.file_ = std::move(bytes);
    return f;
}

const TensorInfo* SafetensorsFile::find(const std::string& name) const {
    for (const TensorInfo& t : tensors_) if (t.name == name) return &t;
    return nullptr;
}

const TensorInfo& SafetensorsFile::at(const std::string& name) const {
    const TensorInfo* t = find(name);
    if (!t) throw Error(source_ + ": no tensor named '" + name + "'");
    return *t;
}

std::span<const uint8_t> SafetensorsFile::bytes(const TensorInfo& t) const {
    return {file_.data() + data_start_ + t.begin, size_t(t.end - t.begin)};
}

std::vector<float> SafetensorsFile::to_f32(const TensorInfo& t) const {
    auto b = bytes(t);
    size_t n = size_t(numel(t.shape));
    std::vector<float> out(n);
    switch (t.dtype) {
        case DType::F32: if (n) std::memcpy(out.data(), b.data(), n * 4); break;
        case DType::F16:
            for (size_t i = 0; i < n; ++i) {
                uint16_t h;
                std::memcpy(&h, b.data() + 2 * i, 2);
                out[i] = half_to_float(h);
            }
            break;
        case DType::BF16:
            for (size_t i = 0; i < n; ++i) {
                uint16_t h;
                std::memcpy(&h, b.data() + 2 * i, 2);
                out[i] = std::bit_cast<float>(uint32_t(h) << 16);
            }
            break;
        default:
            throw Error(source_ + ": tensor '" + t.name + "' has dtype " + dtype_name(t.dtype) +
                        ", expected a float dtype");
    }
    return out;
}

std::vector<int32_t> SafetensorsFile::to_i32(const TensorInfo& t) const {
    auto b = bytes(t);
    size_t n = size_t(numel(t.shape));
    std::vector<int32_t> out(n);
    auto narrow = [&](int64_t v) {
        if (v < std::numeric_limits<int32_t>::min() || v > std::numeric_limits<int32_t>::max())
            throw Error(source_ + ": tensor '" + t.name + "' holds a value outside int32");
        return int32_t(v);
    };
    for (size_t i = 0; i < n; ++i) {
        switch (t.dtype) {
            case DType::I32: std::memcpy(&out[i], b.data() + 4 * i, 4); break;
            case DType::I64: { int64_t v; std::memcpy(&v, b.data() + 8 * i, 8); out[i] = narrow(v); break; }
            case DType::I16: { int16_t v; std::memcpy(&v, b.data() + 2 * i, 2); out[i] = v; break; }
            case DType::I8: out[i] = int8_t(b[i]); break;
            case DType::U8: case DType::BOOL: out[i] = b[i]; break;
            default:
                throw Error(source_ + ": tensor '" + t.name + "' has dtype " + dtype_name(t.dtype) +
                            ", expected an integer dtype");
        }
    }
    return out;
}

TensorBlob TensorBlob::f32(std::string name, Shape shape, const std::vector<float>& v) {
    TensorBlob b{std::move(name), DType::F32, std::move(shape), {}};
    b.bytes.resize(v.size() * 4);
    if (!v.empty()) std::memcpy(b.bytes.data(), v.data(), b.bytes.size());  // data() of empty: maybe null
    return b;
}

TensorBlob TensorBlob::i32(std::string name, Shape shape, const std::vector<int32_t>& v) {
    TensorBlob b{std::move(name), DType::I32, std::move(shape), {}};
    b.bytes.resize(v.size() * 4);
    if (!v.empty()) std::memcpy(b.bytes.data(), v.data(), b.bytes.size());
    return b;
}

void write_safetensors(const std::string& path, const std::vector<TensorBlob>& tensors,
                       const std::map<std::string, std::string>& metadata) {
    nlohmann::json header = nlohmann::json::object();
    if (!metadata.empty()) header["__metadata__"] = metadata;
    uint64_t offset = 0;
    for (const TensorBlob& t : tensors) {
        if (t.bytes.size() != uint64_t(numel(t.shape)) * dtype_size(t.dtype))
            throw Error("write_safetensors: tensor '" + t.name + "' has the wrong byte count");
        header[t.name] = {{"dtype", dtype_name(t.dtype)},
                          {"shape", t.shape},
                          {"data_offsets", {offset, offset + t.bytes.size()}}};
        offset += t.bytes.size();
    }
    std::string text = header.dump();
    text.append((8 - text.size() % 8) % 8, ' ');
    uint64_t len = text.size();
    std::string bytes(reinterpret_cast<const char*>(&len), 8);
    bytes += text;
    for (const TensorBlob& t : tensors) bytes.append(reinterpret_cast<const char*>(t.bytes.data()), t.bytes.size());
    write_file_atomic(path, bytes);
}

}  // namespace vtloc
