#pragma once
// Host-side tensors: shapes and fp32 data. Device tensors are views into
// arenas (see engine/graph.h); these are what users and CPU references see.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace vtloc {

using Shape = std::vector<int64_t>;

inline int64_t numel(const Shape& s) {
    int64_t n = 1;
    for (int64_t d : s) n *= d;
    return n;
}

inline std::string shape_str(const Shape& s) {
    std::string out = "[";
    for (size_t i = 0; i < s.size(); ++i) out += (i ? ", " : "") + std::to_string(s[i]);
    return out + "]";
}

// Element types of graph values; both are 32 bits, so memory planning and
// copies never depend on the type.
enum class ElemType : uint8_t { F32, I32 };
inline const char* elem_type_name(ElemType t) { return t == ElemType::F32 ? "F32" : "I32"; }

// Shape and element type of a graph value (what shape inference produces).
struct TensorDesc {
    Shape shape;
    ElemType type = ElemType::F32;
    TensorDesc(Shape s = {}, ElemType t = ElemType::F32) : shape(std::move(s)), type(t) {}
};

struct HostTensor {
    Shape shape;
    ElemType type = ElemType::F32;
    // I32 tensors keep their 32-bit integers bit for bit in this storage; use
    // ints() / int_at() / set_int() to read and write them.
    std::vector<float> data;

    HostTensor() = default;
    explicit HostTensor(Shape s, ElemType t = ElemType::F32)
        : shape(std::move(s)), type(t), data(size_t(numel(shape)), 0.0f) {}
    HostTensor(Shape s, std::vector<float> d) : shape(std::move(s)), data(std::move(d)) {}
    static HostTensor from_ints(Shape s, const std::vector<int32_t>& v) {
        HostTensor t(std::move(s), ElemType::I32);
        if (!v.empty()) std::memcpy(t.data.data(), v.data(), v.size() * 4);  // data() of empty: maybe null
        return t;
    }
    int64_t size() const { return int64_t(data.size()); }
    int32_t int_at(size_t i) const {
        int32_t v;
        std::memcpy(&v, &data[i], 4);
        return v;
    }
    void set_int(size_t i, int32_t v) { std::memcpy(&data[i], &v, 4); }
    std::vector<int32_t> ints() const {
        std::vector<int32_t> v(data.size());
        if (!data.empty()) std::memcpy(v.data(), data.data(), data.size() * 4);
        return v;
    }
};

}  // namespace vtloc
