#pragma once
// Host-side tensors: shapes and fp32 data. Device tensors are views into
// arenas (see engine/graph.h); these are what users and CPU references see.
#include <cstdint>
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

struct HostTensor {
    Shape shape;
    std::vector<float> data;

    HostTensor() = default;
    explicit HostTensor(Shape s) : shape(std::move(s)), data(size_t(numel(shape)), 0.0f) {}
    HostTensor(Shape s, std::vector<float> d) : shape(std::move(s)), data(std::move(d)) {}
    int64_t size() const { return int64_t(data.size()); }
};

}  // namespace vtloc
