#pragma once
// What a compute shader's SPIR-V declares for set 0 and its push constants, read
// from the module itself, so a pipeline is checked against the shader it runs
// rather than against counts written by hand in the op.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace vtloc::rt {

enum class BindingKind { StorageBuffer, TexelBuffer, UniformBuffer, Other };

struct ShaderInterface {
    std::vector<BindingKind> bindings;  // index = binding number in set 0; gaps are Other
    uint32_t push_bytes = 0;            // size of the push-constant block (0: none)
    bool subgroup_ops = false;          // declares a GroupNonUniform* capability
};

// Throws vtloc::Error naming `shader` when the words are not a SPIR-V module this
// reader understands.
ShaderInterface reflect_spirv(std::span<const uint32_t> words, const std::string& shader);

}  // namespace vtloc::rt
