#pragma once
// Vulkan instance + one compute queue on one physical device.
// Vulkan 1.1 core only; no device extension is required.
#include <vulkan/vulkan.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace vtloc::rt {

class PipelineCache;

// The device properties that shaders and tile choices depend on.
struct DeviceInfo {
    uint32_t index = 0;
    std::string name;
    VkPhysicalDeviceType type = VK_PHYSICAL_DEVICE_TYPE_OTHER;
    uint32_t api_version = 0;
    uint32_t driver_version = 0;
    uint32_t vendor_id = 0;
    uint32_t subgroup_size = 1;
    // VkSubgroupFeatureFlags usable in compute shaders (0 when compute has none).
    uint32_t subgroup_ops = 0;
    uint32_t max_shared_memory = 0;           // bytes per workgroup
    uint32_t max_invocations = 0;             // per workgroup
    std::array<uint32_t, 3> max_workgroup_size{};
    std::array<uint32_t, 3> max_workgroup_count{};
    uint64_t max_storage_buffer_range = 0;
    uint64_t storage_offset_alignment = 1;
    uint32_t max_push_constants = 0;
    uint32_t max_storage_buffers = 0;         // per shader stage (Vulkan guarantees only 4)
    // Uniform texel buffers (read-only samplerBuffer bindings, see PipelineDesc).
    uint64_t texel_offset_alignment = 1;      // minTexelBufferOffsetAlignment
    uint32_t max_texel_elements = 0;          // maxTexelBufferElements (Vulkan guarantees 65536)
    // Uniform buffers (PipelineDesc::uniform_bindings): small read-only data every
    // lane reads at the same address.
    uint64_t uniform_offset_alignment = 1;    // minUniformBufferOffsetAlignment
    uint64_t max_uniform_range = 0;           // maxUniformBufferRange (Vulkan guarantees 16384)
    float timestamp_period = 0.0f;            // ns per tick
    bool has_timestamps = false;
    bool has_compute_queue = false;
    uint64_t device_local_bytes = 0;
    // CPU devices only (0 for GPUs): the vector registers of the host CPU that the
    // driver's JIT code runs on, 32 with AVX-512VL or on AArch64, else 16. No Vulkan
    // limit exposes them; a CPU driver's speed depends on them, so `vtloc devices`,
    // `vtloc check` and the bench report them (group_linear's tile read them until
    // 8 x 32 measured best with 16 as well: group_linear.cpp).
    uint32_t host_vector_registers = 0;  // rt::host_vector_registers()
    // GPUs: compute units (NVIDIA SMs, AMD CUs, Arm shader cores) where the driver
    // says (VK_NV_shader_sm_builtins, VK_AMD_shader_core_properties,
    // VK_ARM_shader_core_builtins) or a device profile does; 0: unknown. Tile
    // choices aim to give each of them several workgroups (fill_workgroups).
    uint32_t compute_units = 0;
    // Offset alignment of any tensor: it may be bound as a storage, texel or uniform buffer.
    uint64_t tensor_alignment() const {
        return std::max<uint64_t>({16, storage_offset_alignment, texel_offset_alignment, uniform_offset_alignment});
    }
};

// How many workgroups a dispatch should offer to keep the device busy: four per
// compute unit on a GPU (16 units assumed where the driver does not say), the host's
// threads on a CPU device. Tile choices shrink their blocks towards it.
uint64_t fill_workgroups(const DeviceInfo& d);

// The host's vector registers as lavapipe's JIT code sees them (DeviceInfo's
// host_vector_registers on CPU devices): 32 with AVX-512VL or on AArch64, else
// 16, and 16 where GALLIUM_OVERRIDE_CPU_CAPS (nosse .. avx) or GALLIUM_NOSSE
// holds Mesa's JIT below AVX-512.
uint32_t host_vector_registers();
// GALLIUM_OVERRIDE_CPU_CAPS or GALLIUM_NOSSE holds Mesa's JIT below AVX-512.
bool mesa_jit_below_avx512();

const char* device_type_name(VkPhysicalDeviceType t);
// Whether the physical device offers a device extension (false where it cannot be asked).
bool has_device_extension(VkPhysicalDevice pd, const char* name);

struct ContextOptions {
    // Empty: VTLOC_VALIDATION decides (1/on/true turns the Khronos layer on).
    int validation = -1;  // -1 from env, 0 off, 1 on
    // Empty: VTLOC_DEVICE decides; otherwise a device index or a name substring.
    std::string device;
    // Bytes of buffers (device and staging) this context may hold at once; 0:
    // VTLOC_MEMORY_BUDGET_MIB if set, else no limit beyond the device's own. Past
    // it an allocation fails as out-of-device-memory would, with a clear error.
    uint64_t memory_budget = 0;
    // Plan only (rt/device_profile.h): the context reports these limits instead of
    // its own device's, pipelines are checked against them but not compiled, and
    // sequences record dispatches without running them (a submit that holds one
    // throws). Buffers are still real, on the device picked above.
    std::optional<DeviceInfo> plan_for;
    // Texel-buffer elements the engine may use (0: VTLOC_MAX_TEXEL_ELEMENTS if set, else the
    // device's): below the device's own, the ops take the storage-buffer paths a device with
    // that limit would, on this one (vtloc check --tracker at a small GPU's limit). At least
    // Vulkan's guaranteed 65,536.
    uint32_t max_texel_elements = 0;
};

// A message from the validation layer (warnings and errors only).
struct ValidationMessage {
    std::string severity;
    std::string text;
};

class Context {
public:
    explicit Context(const ContextOptions& options = {});
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    // All Vulkan devices with compute, in enumeration order (no logical device made).
    static std::vector<DeviceInfo> list_devices();

    VkInstance instance() const { return instance_; }
    VkPhysicalDevice physical_device() const { return physical_; }
    VkDevice device() const { return device_; }
    VkQueue queue() const { return queue_; }
    uint32_t queue_family() const { return queue_family_; }
    const DeviceInfo& info() const { return info_; }
    bool validation_enabled() const { return messenger_ != VK_NULL_HANDLE; }
    // Made with ContextOptions::plan_for: info() is the profile's; nothing runs.
    bool plan_only() const { return plan_only_; }
    PipelineCache& pipelines() { return *pipelines_; }

    // Memory type index with all of `required` (and `preferred` where possible).
    uint32_t memory_type(uint32_t type_bits, VkMemoryPropertyFlags required,
                         VkMemoryPropertyFlags preferred) const;

    // Validation messages seen since the last take (thread-safe).
    std::vector<ValidationMessage> take_validation_messages();
    size_t validation_message_count() const;

    // Called by the debug messenger; public only for the C callback.
    void on_validation_message(const ValidationMessage& m);

    // Buffer bookkeeping against the memory budget (memory.cpp): reserve throws
    // vtloc::Error when `bytes` more would pass it.
    void reserve_memory(uint64_t bytes);
    void release_memory(uint64_t bytes) { in_use_ -= bytes; }
    uint64_t memory_in_use() const { return in_use_; }
    uint64_t memory_budget() const { return budget_; }

    // After VK_ERROR_DEVICE_LOST (real, or simulated by testing::lose_device)
    // the context refuses all further GPU work with a clear error.
    void mark_lost() { lost_ = true; }
    bool lost() const { return lost_; }
    void check_not_lost() const;
    // Test hook: the next submit fails with VK_ERROR_DEVICE_LOST instead of running.
    void simulate_device_loss() { simulate_loss_ = true; }
    bool take_simulated_loss() { return simulate_loss_.exchange(false); }

    // vkQueueSubmit needs the queue externally synchronised: every submit on this
    // context (from any thread: models, normal estimation) holds this lock.
    std::mutex& queue_mutex() { return queue_mutex_; }

private:
    void release();  // destroys the Vulkan objects; safe on a half-built context

    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkPhysicalDevice physical_ = VK_NULL_HANDLE;
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    uint32_t queue_family_ = 0;
    DeviceInfo info_;
    VkPhysicalDeviceMemoryProperties memory_props_{};
    std::unique_ptr<PipelineCache> pipelines_;
    mutable std::mutex messages_mutex_;
    std::vector<ValidationMessage> messages_;
    uint64_t budget_ = 0;
    std::atomic<uint64_t> in_use_{0};
    std::atomic<bool> lost_{false}, simulate_loss_{false};
    bool plan_only_ = false;
    std::mutex queue_mutex_;
};

// Throws vtloc::Error naming the call when r is not VK_SUCCESS.
void check_vk(VkResult r, const char* what);
const char* vk_result_name(VkResult r);

}  // namespace vtloc::rt
