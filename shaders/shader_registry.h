#pragma once
// SPIR-V embedded at build time (see shaders/CMakeLists.txt).
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace vtloc::rt {
// Empty span when no shader of that name was built.
std::span<const uint32_t> find_spirv(std::string_view name);
std::vector<std::string> embedded_shader_names();
}  // namespace vtloc::rt
