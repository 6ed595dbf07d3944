#include "runtime/pipeline.h"

#include <bit>
#include <chrono>
#include <cstdio>
#include <tuple>

#include "base/env.h"
#include "base/error.h"
#include "runtime/context.h"
#include "runtime/spirv_reflect.h"
#include "shaders/shader_registry.h"

namespace vtloc::rt {

namespace {

// The op's description of the bindings and push constants must be the shader's.
// The op may bind a buffer the shader does not declare (a variant that does not
// read it: the layout just has an unused slot), never the reverse.
void check_interface(const PipelineDesc& desc, const ShaderInterface& iface) {
    const std::string what = "shader '" + desc.shader + "'";
    if (iface.bindings.size() > desc.bindings)
        throw Error(what + " declares " + std::to_string(iface.bindings.size()) + " bindings; the op passes " +
                    std::to_string(desc.bindings));
    for (uint32_t i = 0; i < iface.bindings.size(); ++i) {
        const BindingKind want = (desc.texel_bindings >> i) & 1     ? BindingKind::TexelBuffer
                                 : (desc.uniform_bindings >> i) & 1 ? BindingKind::UniformBuffer
                                                                    : BindingKind::StorageBuffer;
        auto name = [](BindingKind k) {
            return k == BindingKind::TexelBuffer     ? "a texel buffer"
                   : k == BindingKind::UniformBuffer ? "a uniform buffer"
                                                     : "a storage buffer";
        };
        if (iface.bindings[i] != want && iface.bindings[i] != BindingKind::Other)
            throw Error(what + ": binding " + std::to_string(i) + " is " + name(iface.bindings[i]) +
                        " in the shader, but the op binds " + name(want));
    }
    if (iface.push_bytes != desc.push_bytes)
        throw Error(what + " declares " + std::to_string(iface.push_bytes) + " bytes of push constants; the op pushes " +
                    std::to_string(desc.push_bytes));
}

// VTLOC_TRACE_PIPELINES=1 (as VTLOC_VALIDATION): a line on stderr per pipeline created, so
// that a developer sees what a run compiles. On a CPU driver (lavapipe) most of a cold
// pipeline's cost comes at its first dispatch, which this time does not include.
bool trace_pipelines() {
    static const bool on = env_flag("VTLOC_TRACE_PIPELINES");
    return on;
}

void trace(const PipelineDesc& desc, std::chrono::steady_clock::time_point t0) {
    std::string line = "vtloc: pipeline ";  // appended, not "..." + s: GCC 12 warns falsely (-Wrestrict) there
    line += desc.shader;
    line += ", spec";
    for (uint32_t v : desc.spec) line += ' ' + std::to_string(v);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "%s, created in %.1f ms\n", line.c_str(), ms);
}

}  // namespace

bool PipelineDesc::operator<(const PipelineDesc& o) const {
    return std::tie(shader, bindings, push_bytes, spec, texel_bindings, uniform_bindings) <
           std::tie(o.shader, o.bindings, o.push_bytes, o.spec, o.texel_bindings, o.uniform_bindings);
}

size_t PipelineCache::size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return pipelines_.size();
}

const Pipeline& PipelineCache::get(const PipelineDesc& desc) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = pipelines_.find(desc);
    if (it != pipelines_.end()) return *it->second;

    const auto t0 = std::chrono::steady_clock::now();
    const DeviceInfo& info = ctx_.info();
    auto spirv = find_spirv(desc.shader);
    if (spirv.empty()) throw Error("no embedded shader named '" + desc.shader + "'");
    if (desc.push_bytes > info.max_push_constants)
        throw Error("shader '" + desc.shader + "' needs " + std::to_string(desc.push_bytes) +
                    " bytes of push constants; the device allows " +
                    std::to_string(info.max_push_constants));
    // Texel buffers count against maxPerStageDescriptorSampledImages (at least 16).
    const uint32_t storage =
        desc.bindings - uint32_t(std::popcount(desc.texel_bindings)) - uint32_t(std::popcount(desc.uniform_bindings));
    if (desc.texel_bindings >> desc.bindings)
        throw Error("shader '" + desc.shader + "': texel binding mask names a binding it does not have");
    if (desc.uniform_bindings >> desc.bindings || (desc.uniform_bindings & desc.texel_bindings))
        throw Error("shader '" + desc.shader + "': uniform binding mask names a binding it does not have, or a texel one");
    if (storage > info.max_storage_buffers)
        throw Error("shader '" + desc.shader + "' binds " + std::to_string(storage) +
                    " storage buffers; the device allows " + std::to_string(info.max_storage_buffers) +
                    " per stage");
    uint32_t lx = desc.spec.empty() ? 1 : desc.spec[0];
    if (lx == 0 || lx > info.max_workgroup_size[0] || lx > info.max_invocations)
        throw Error("shader '" + desc.shader + "': workgroup size " + std::to_string(lx) +
                    " is outside the device's limits");
    check_interface(desc, reflect_spirv(spirv, desc.shader));

    VkDevice dev = ctx_.device();
    auto p = std::make_unique<Pipeline>();
    p->desc = desc;
    if (ctx_.plan_only()) return *(pipelines_[desc] = std::move(p));  // checked against the profile, never compiled

    std::vector<VkDescriptorSetLayoutBinding> binds(desc.bindings);
    for (uint32_t i = 0; i < desc.bindings; ++i) {
        binds[i] = {};
        binds[i].binding = i;
        binds[i].descriptorType = (desc.texel_bindings >> i) & 1     ? VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER
                                  : (desc.uniform_bindings >> i) & 1 ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER
                                                                     : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        binds[i].descriptorCount = 1;
        binds[i].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
    }
    VkDescriptorSetLayoutCreateInfo dl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    dl.bindingCount = desc.bindings;
    dl.pBindings = binds.data();
    check_vk(vkCreateDescriptorSetLayout(dev, &dl, nullptr, p->set_layout.out(dev)), "vkCreateDescriptorSetLayout");

    VkPushConstantRange pc{VK_SHADER_STAGE_COMPUTE_BIT, 0, desc.push_bytes};
    VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pl.setLayoutCount = 1;
    pl.pSetLayouts = p->set_layout.ptr();
    pl.pushConstantRangeCount = desc.push_bytes ? 1 : 0;
    pl.pPushConstantRanges = &pc;
    check_vk(vkCreatePipelineLayout(dev, &pl, nullptr, p->layout.out(dev)), "vkCreatePipelineLayout");

    VkShaderModuleCreateInfo sm{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    sm.codeSize = spirv.size() * sizeof(uint32_t);
    sm.pCode = spirv.data();
    ShaderModuleHandle module;
    check_vk(vkCreateShaderModule(dev, &sm, nullptr, module.out(dev)), "vkCreateShaderModule");

    std::vector<VkSpecializationMapEntry> entries(desc.spec.size());
    for (uint32_t i = 0; i < desc.spec.size(); ++i)
        entries[i] = {i, uint32_t(i * sizeof(uint32_t)), sizeof(uint32_t)};
    VkSpecializationInfo si{};
    si.mapEntryCount = uint32_t(entries.size());
    si.pMapEntries = entries.data();
    si.dataSize = desc.spec.size() * sizeof(uint32_t);
    si.pData = desc.spec.data();

    VkComputePipelineCreateInfo ci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    ci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    ci.stage.module = module.get();
    ci.stage.pName = "main";
    ci.stage.pSpecializationInfo = desc.spec.empty() ? nullptr : &si;
    ci.layout = p->layout.get();
    check_vk(vkCreateComputePipelines(dev, VK_NULL_HANDLE, 1, &ci, nullptr, p->pipeline.out(dev)),
             ("vkCreateComputePipelines for shader " + desc.shader).c_str());
    if (trace_pipelines()) trace(desc, t0);
    return *(pipelines_[desc] = std::move(p));
}

}  // namespace vtloc::rt
