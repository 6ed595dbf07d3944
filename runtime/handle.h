#pragma once
// Owning Vulkan handles: each is destroyed exactly once, on every path (errors
// included), and members go in reverse order of declaration, so a struct that
// declares a layout before the pipeline using it tears them down correctly.
#include <vulkan/vulkan.h>

#include <utility>

namespace vtloc::rt {

template <typename T, void (*Destroy)(VkDevice, T, const VkAllocationCallbacks*)>
class DeviceHandle {
public:
    DeviceHandle() = default;
    ~DeviceHandle() { reset(); }
    DeviceHandle(DeviceHandle&& o) noexcept : dev_(o.dev_), h_(std::exchange(o.h_, T(VK_NULL_HANDLE))) {}
    DeviceHandle& operator=(DeviceHandle&& o) noexcept {
        if (this != &o) {
            reset();
            dev_ = o.dev_;
            h_ = std::exchange(o.h_, T(VK_NULL_HANDLE));
        }
        return *this;
    }
    DeviceHandle(const DeviceHandle&) = delete;
    DeviceHandle& operator=(const DeviceHandle&) = delete;

    void reset() {
        if (h_ != VK_NULL_HANDLE) Destroy(dev_, h_, nullptr);
        h_ = VK_NULL_HANDLE;
    }
    T get() const { return h_; }
    const T* ptr() const { return &h_; }
    explicit operator bool() const { return h_ != VK_NULL_HANDLE; }
    // Where a vkCreate* call writes the new handle; `dev` destroys it later.
    T* out(VkDevice dev) {
        reset();
        dev_ = dev;
        return &h_;
    }

private:
    VkDevice dev_ = VK_NULL_HANDLE;
    T h_ = VK_NULL_HANDLE;
};

using PipelineHandle = DeviceHandle<VkPipeline, vkDestroyPipeline>;
using PipelineLayoutHandle = DeviceHandle<VkPipelineLayout, vkDestroyPipelineLayout>;
using SetLayoutHandle = DeviceHandle<VkDescriptorSetLayout, vkDestroyDescriptorSetLayout>;
using ShaderModuleHandle = DeviceHandle<VkShaderModule, vkDestroyShaderModule>;
using CommandPoolHandle = DeviceHandle<VkCommandPool, vkDestroyCommandPool>;
using FenceHandle = DeviceHandle<VkFence, vkDestroyFence>;
using DescriptorPoolHandle = DeviceHandle<VkDescriptorPool, vkDestroyDescriptorPool>;
using BufferViewHandle = DeviceHandle<VkBufferView, vkDestroyBufferView>;
using QueryPoolHandle = DeviceHandle<VkQueryPool, vkDestroyQueryPool>;
using BufferHandle = DeviceHandle<VkBuffer, vkDestroyBuffer>;
using MemoryHandle = DeviceHandle<VkDeviceMemory, vkFreeMemory>;

}  // namespace vtloc::rt
