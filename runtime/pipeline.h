#pragma once
// Compute pipelines, created once per (shader, specialization constants) and cached.
// Conventions every shader follows:
//   - bindings 0..n-1 of set 0 are storage buffers (or texel / uniform buffers
//     where PipelineDesc says so), in the order the op passes them;
//   - specialization constant 0 is local_size_x (the host picks it from device limits);
//   - constants 1.. are the shader's own (tile sizes, modes), 32-bit each;
//   - small per-dispatch numbers go in push constants.
#include <vulkan/vulkan.h>

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "runtime/handle.h"

namespace vtloc::rt {

class Context;

struct PipelineDesc {
    std::string shader;            // name of shaders/<name>.comp
    uint32_t bindings = 0;         // storage buffers (some may be texel buffers, below)
    uint32_t push_bytes = 0;       // push-constant block size
    std::vector<uint32_t> spec;    // constant_id i = spec[i]; spec[0] = local_size_x
    // Bit i set: binding i is a uniform texel buffer (a read-only samplerBuffer read
    // with texelFetch) instead of a storage buffer. On CPU devices a texel fetch is a
    // branch-free gather while a storage-buffer load is a loop over the lanes.
    uint32_t texel_bindings = 0;
    // Bit i set: binding i is a uniform buffer. On CPU devices a uniform-buffer load
    // at an address every lane shares is one load and a broadcast, where a
    // storage-buffer load is still a loop over the lanes (docs/performance.md "On CPUs without AVX-512, measured").
    uint32_t uniform_bindings = 0;

    bool operator<(const PipelineDesc& o) const;
};

struct Pipeline {
    // Declared in creation order; destroyed in reverse.
    SetLayoutHandle set_layout;
    PipelineLayoutHandle layout;
    PipelineHandle pipeline;
    PipelineDesc desc;
    uint32_t local_size_x() const { return desc.spec.empty() ? 1 : desc.spec[0]; }
};

class PipelineCache {
public:
    explicit PipelineCache(Context& ctx) : ctx_(ctx) {}
    PipelineCache(const PipelineCache&) = delete;
    PipelineCache& operator=(const PipelineCache&) = delete;

    // Thread-safe; the returned reference lives as long as the cache.
    const Pipeline& get(const PipelineDesc& desc);
    size_t size() const;

private:
    Context& ctx_;
    mutable std::mutex mutex_;
    std::map<PipelineDesc, std::unique_ptr<Pipeline>> pipelines_;
};

}  // namespace vtloc::rt
