#include "runtime/context.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <strings.h>
#include <thread>
#include <utility>

#include "base/env.h"
#include "base/error.h"
#include "runtime/pipeline.h"

namespace vtloc::rt {

const char* vk_result_name(VkResult r) {
    switch (r) {
        case VK_SUCCESS: return "VK_SUCCESS";
        case VK_NOT_READY: return "VK_NOT_READY";
        case VK_TIMEOUT: return "VK_TIMEOUT";
        case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
        case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
        case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
        case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
        case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
        case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
        case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
        case VK_ERROR_TOO_MANY_OBJECTS: return "VK_ERROR_TOO_MANY_OBJECTS";
        case VK_ERROR_OUT_OF_POOL_MEMORY: return "VK_ERROR_OUT_OF_POOL_MEMORY";
        default: return "VkResult error";
    }
}

void check_vk(VkResult r, const char* what) {
    if (r != VK_SUCCESS)
        throw Error(std::string("Vulkan: ") + what + " failed with " + vk_result_name(r) +
                    " (" + std::to_string(int(r)) + ")");
}

const char* device_type_name(VkPhysicalDeviceType t) {
    switch (t) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
        case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
        default: return "other";
    }
}

namespace {

VKAPI_ATTR VkBool32 VKAPI_CALL debug_callback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                              VkDebugUtilsMessageTypeFlagsEXT,
                                              const VkDebugUtilsMessengerCallbackDataEXT* data,
                                              void* user) {
    ValidationMessage m;
    m.severity = (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) ? "error" : "warning";
    m.text = data && data->pMessage ? data->pMessage : "(no text)";
    static_cast<Context*>(user)->on_validation_message(m);
    return VK_FALSE;
}

bool has_layer(const char* name) {
    uint32_t n = 0;
    vkEnumerateInstanceLayerProperties(&n, nullptr);
    std::vector<VkLayerProperties> layers(n);
    vkEnumerateInstanceLayerProperties(&n, layers.data());
    for (auto& l : layers)
        if (std::strcmp(l.layerName, name) == 0) return true;
    return false;
}

VkInstance make_instance(bool validation) {
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "vtloc";
    app.pEngineName = "vtloc";
    app.apiVersion = VK_API_VERSION_1_1;
    VkInstanceCreateInfo ci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ci.pApplicationInfo = &app;
    const char* layer = "VK_LAYER_KHRONOS_validation";
    const char* ext = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    if (validation) {
        if (!has_layer(layer))
            throw Error("validation was requested but VK_LAYER_KHRONOS_validation is not "
                        "installed (Debian: apt-get install vulkan-validationlayers)");
        ci.enabledLayerCount = 1;
        ci.ppEnabledLayerNames = &layer;
        ci.enabledExtensionCount = 1;
        ci.ppEnabledExtensionNames = &ext;
    }
    VkInstance inst = VK_NULL_HANDLE;
    VkResult r = vkCreateInstance(&ci, nullptr, &inst);
    if (r == VK_ERROR_INCOMPATIBLE_DRIVER)
        throw Error("no Vulkan driver found (Debian: apt-get install mesa-vulkan-drivers for "
                    "the lavapipe CPU device)");
    check_vk(r, "vkCreateInstance");
    return inst;
}

std::vector<VkPhysicalDevice> physical_devices(VkInstance inst) {
    uint32_t n = 0;
    check_vk(vkEnumeratePhysicalDevices(inst, &n, nullptr), "vkEnumeratePhysicalDevices");
    std::vector<VkPhysicalDevice> devs(n);
    check_vk(vkEnumeratePhysicalDevices(inst, &n, devs.data()), "vkEnumeratePhysicalDevices");
    return devs;
}

int compute_queue_family(VkPhysicalDevice pd) {
    uint32_t n = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
    std::vector<VkQueueFamilyProperties> fams(n);
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, fams.data());
    // Prefer a compute queue that also does graphics: it is the one that has
    // timestamps everywhere; a dedicated async-compute family is no faster here.
    int best = -1;
    for (uint32_t i = 0; i < n; ++i) {
        if (!(fams[i].queueFlags & VK_QUEUE_COMPUTE_BIT)) continue;
        if (best < 0 || (fams[i].queueFlags & VK_QUEUE_GRAPHICS_BIT)) best = int(i);
        if (fams[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) break;
    }
    return best;
}

}  // namespace

bool has_device_extension(VkPhysicalDevice pd, const char* name) {
    uint32_t n = 0;
    if (vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, nullptr) != VK_SUCCESS) return false;
    std::vector<VkExtensionProperties> ext(n);
    if (vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, ext.data()) != VK_SUCCESS) return false;
    for (const auto& e : ext)
        if (std::strcmp(e.extensionName, name) == 0) return true;
    return false;
}

namespace {

DeviceInfo query_info(VkPhysicalDevice pd, uint32_t index) {
    VkPhysicalDeviceSubgroupProperties sub{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
    VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    p2.pNext = &sub;
    // The compute units, from whichever vendor extension the driver has (chained only then).
    VkPhysicalDeviceShaderSMBuiltinsPropertiesNV nv{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_SM_BUILTINS_PROPERTIES_NV};
    VkPhysicalDeviceShaderCorePropertiesAMD amd{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_CORE_PROPERTIES_AMD};
    VkPhysicalDeviceShaderCoreBuiltinsPropertiesARM arm{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_CORE_BUILTINS_PROPERTIES_ARM};
    void** tail = &sub.pNext;
    auto chain = [&](auto& s, const char* ext) {
        if (!has_device_extension(pd, ext)) return false;
        *tail = &s;
        tail = &s.pNext;
        return true;
    };
    const bool has_nv = chain(nv, VK_NV_SHADER_SM_BUILTINS_EXTENSION_NAME);
    const bool has_amd = chain(amd, VK_AMD_SHADER_CORE_PROPERTIES_EXTENSION_NAME);
    const bool has_arm = chain(arm, VK_ARM_SHADER_CORE_BUILTINS_EXTENSION_NAME);
    vkGetPhysicalDeviceProperties2(pd, &p2);
    const VkPhysicalDeviceProperties& p = p2.properties;
    const VkPhysicalDeviceLimits& l = p.limits;
    DeviceInfo d;
    d.index = index;
    d.name = p.deviceName;
    d.type = p.deviceType;
    d.api_version = p.apiVersion;
    d.driver_version = p.driverVersion;
    d.vendor_id = p.vendorID;
    d.subgroup_size = std::max(1u, sub.subgroupSize);
    d.subgroup_ops = (sub.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) ? sub.supportedOperations : 0u;
    d.max_shared_memory = l.maxComputeSharedMemorySize;
    d.max_invocations = l.maxComputeWorkGroupInvocations;
    for (int i = 0; i < 3; ++i) {
        d.max_workgroup_size[i] = l.maxComputeWorkGroupSize[i];
        d.max_workgroup_count[i] = l.maxComputeWorkGroupCount[i];
    }
    d.max_storage_buffer_range = l.maxStorageBufferRange;
    d.storage_offset_alignment = std::max<uint64_t>(1, l.minStorageBufferOffsetAlignment);
    d.max_push_constants = l.maxPushConstantsSize;
    d.max_storage_buffers = l.maxPerStageDescriptorStorageBuffers;
    d.texel_offset_alignment = std::max<uint64_t>(1, l.minTexelBufferOffsetAlignment);
    d.max_texel_elements = l.maxTexelBufferElements;
    d.uniform_offset_alignment = std::max<uint64_t>(1, l.minUniformBufferOffsetAlignment);
    d.max_uniform_range = l.maxUniformBufferRange;
    d.timestamp_period = l.timestampPeriod;
    int fam = compute_queue_family(pd);
    d.has_compute_queue = fam >= 0;
    if (fam >= 0) {
        uint32_t n = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
        std::vector<VkQueueFamilyProperties> fams(n);
        vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, fams.data());
        d.has_timestamps = fams[fam].timestampValidBits > 0 && l.timestampPeriod > 0.0f;
    }
    VkPhysicalDeviceMemoryProperties mp;
    vkGetPhysicalDeviceMemoryProperties(pd, &mp);
    for (uint32_t i = 0; i < mp.memoryHeapCount; ++i)
        if (mp.memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
            d.device_local_bytes += mp.memoryHeaps[i].size;
    if (d.type == VK_PHYSICAL_DEVICE_TYPE_CPU) d.host_vector_registers = host_vector_registers();
    if (has_nv) d.compute_units = nv.shaderSMCount;
    else if (has_amd) d.compute_units = amd.shaderEngineCount * amd.shaderArraysPerEngineCount * amd.computeUnitsPerShaderArray;
    else if (has_arm) d.compute_units = arm.shaderCoreCount;
    return d;
}

int type_rank(VkPhysicalDeviceType t) {
    switch (t) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
        case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
        default: return 4;
    }
}

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), ::tolower);
    return s;
}

// discrete > integrated > virtual > CPU, unless `want` names one (index or name substring).
size_t choose_device(const std::vector<DeviceInfo>& devs, const std::string& want) {
    std::string names;
    for (auto& d : devs) names += "\n  " + std::to_string(d.index) + ": " + d.name;
    if (!want.empty()) {
        bool numeric = std::all_of(want.begin(), want.end(), ::isdigit);
        for (size_t i = 0; i < devs.size(); ++i) {
            if (!devs[i].has_compute_queue) continue;
            if (numeric ? devs[i].index == std::stoul(want)
                        : lower(devs[i].name).find(lower(want)) != std::string::npos)
                return i;
        }
        throw Error("no Vulkan compute device matches VTLOC_DEVICE='" + want + "'; devices:" + names);
    }
    size_t best = devs.size();
    for (size_t i = 0; i < devs.size(); ++i) {
        if (!devs[i].has_compute_queue || devs[i].api_version < VK_API_VERSION_1_1) continue;
        if (best == devs.size() || type_rank(devs[i].type) < type_rank(devs[best].type)) best = i;
    }
    if (best == devs.size()) throw Error("no Vulkan 1.1 device with a compute queue; devices:" + names);
    return best;
}

}  // namespace

// lavapipe's LLVM targets the host CPU's features; AVX-512VL gives its 256-bit
// code 32 ymm registers instead of AVX2's 16 (x86-64 only: 32-bit mode has 8).
// Mesa lets a user hold its JIT below the CPU (util/u_cpu_detect.c): each
// GALLIUM_OVERRIDE_CPU_CAPS level it knows, and GALLIUM_NOSSE, turn AVX-512 off.
bool mesa_jit_below_avx512() {
    if (const char* o = std::getenv("GALLIUM_OVERRIDE_CPU_CAPS"))
        for (const char* level : {"nosse", "sse", "sse2", "sse3", "ssse3", "sse4.1", "avx"})
            if (std::strcmp(o, level) == 0) return true;
    if (const char* n = std::getenv("GALLIUM_NOSSE"))  // Mesa's boolean words, any case
        for (const char* yes : {"1", "y", "yes", "t", "true"})
            if (strcasecmp(n, yes) == 0) return true;
    return false;
}

uint32_t host_vector_registers() {
#if defined(__aarch64__)
    return 32;
#elif defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    if (mesa_jit_below_avx512()) return 16;
    return __builtin_cpu_supports("avx512vl") ? 32 : 16;
#else
    return 16;
#endif
}

uint64_t fill_workgroups(const DeviceInfo& d) {
    if (d.type == VK_PHYSICAL_DEVICE_TYPE_CPU) return std::max(1u, std::thread::hardware_concurrency());
    return 4ull * (d.compute_units ? d.compute_units : 16u);
}

std::vector<DeviceInfo> Context::list_devices() {
    VkInstance inst = make_instance(false);
    std::vector<DeviceInfo> out;
    try {
        auto devs = physical_devices(inst);
        for (uint32_t i = 0; i < devs.size(); ++i) out.push_back(query_info(devs[i], i));
    } catch (...) {
        vkDestroyInstance(inst, nullptr);
        throw;
    }
    vkDestroyInstance(inst, nullptr);
    return out;
}

Context::Context(const ContextOptions& options) {
    bool validation = options.validation < 0 ? env_flag("VTLOC_VALIDATION") : options.validation == 1;
    std::string want = options.device;
    if (want.empty() && std::getenv("VTLOC_DEVICE")) want = std::getenv("VTLOC_DEVICE");
    budget_ = options.memory_budget;
    if (const char* mib = std::getenv("VTLOC_MEMORY_BUDGET_MIB"); !budget_ && mib && *mib) {
        char* end = nullptr;
        const double v = std::strtod(mib, &end);
        if (*end || !(v > 0)) throw Error(std::string("VTLOC_MEMORY_BUDGET_MIB='") + mib + "' is not a positive number");
        budget_ = uint64_t(v * 1024 * 1024);
    }

    instance_ = make_instance(validation);
    try {
        if (validation) {
            VkDebugUtilsMessengerCreateInfoEXT mi{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
            mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                                 VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
            mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                             VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                             VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
            mi.pfnUserCallback = debug_callback;
            mi.pUserData = this;
            auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
                vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
            if (!create) throw Error("validation: vkCreateDebugUtilsMessengerEXT is unavailable");
            check_vk(create(instance_, &mi, nullptr, &messenger_), "vkCreateDebugUtilsMessengerEXT");
        }

        auto devs = physical_devices(instance_);
        std::vector<DeviceInfo> infos;
        for (uint32_t i = 0; i < devs.size(); ++i) infos.push_back(query_info(devs[i], i));
        if (infos.empty()) throw Error("no Vulkan device found (is mesa-vulkan-drivers installed?)");
        size_t pick = choose_device(infos, want);
        physical_ = devs[pick];
        info_ = infos[pick];
        queue_family_ = uint32_t(compute_queue_family(physical_));
        vkGetPhysicalDeviceMemoryProperties(physical_, &memory_props_);

        float prio = 1.0f;
        VkDeviceQueueCreateInfo qi{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
        qi.queueFamilyIndex = queue_family_;
        qi.queueCount = 1;
        qi.pQueuePriorities = &prio;
        VkDeviceCreateInfo di{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
        di.queueCreateInfoCount = 1;
        di.pQueueCreateInfos = &qi;
        check_vk(vkCreateDevice(physical_, &di, nullptr, &device_), "vkCreateDevice");
        vkGetDeviceQueue(device_, queue_family_, 0, &queue_);
        uint32_t texel_cap = options.max_texel_elements;
        if (const char* t = std::getenv("VTLOC_MAX_TEXEL_ELEMENTS"); !texel_cap && t && *t) {
            char* end = nullptr;
            const unsigned long long v = std::strtoull(t, &end, 10);
            if (*end || v < 65536 || v > 0xffffffffull)
                throw Error(std::string("VTLOC_MAX_TEXEL_ELEMENTS='") + t + "' is not a whole number from 65536 (Vulkan's minimum) up");
            texel_cap = uint32_t(v);
        }
        if (texel_cap && texel_cap < 65536)
            throw Error("ContextOptions::max_texel_elements " + std::to_string(texel_cap) + " is below Vulkan's minimum, 65536");
        if (texel_cap) info_.max_texel_elements = std::min(info_.max_texel_elements, texel_cap);
        if (options.plan_for) {
            const DeviceInfo real = info_;
            info_ = *options.plan_for;
            info_.index = real.index;
            info_.has_timestamps = false;  // nothing runs: nothing to time
            info_.has_compute_queue = true;
            info_.device_local_bytes = real.device_local_bytes;
            plan_only_ = true;
        }
        pipelines_ = std::make_unique<PipelineCache>(*this);
    } catch (...) {
        release();
        throw;
    }
}

Context::~Context() { release(); }

void Context::reserve_memory(uint64_t bytes) {
    const uint64_t before = in_use_.fetch_add(bytes);
    if (budget_ && before + bytes > budget_) {
        in_use_ -= bytes;
        auto mib = [](uint64_t b) { return std::to_string((b + (1 << 20) - 1) >> 20); };
        throw Error("out of device memory: a " + mib(bytes) + " MiB buffer would bring this context to " +
                    mib(before + bytes) + " MiB, over its budget of " + mib(budget_) +
                    " MiB (ContextOptions::memory_budget / VTLOC_MEMORY_BUDGET_MIB)");
    }
}

void Context::check_not_lost() const {
    if (lost_)
        throw Error("the GPU device of this context was lost (VK_ERROR_DEVICE_LOST) earlier: it refuses further work; "
                    "create a new context");
}

void Context::release() {
    pipelines_.reset();
    if (device_) vkDestroyDevice(device_, nullptr);
    device_ = VK_NULL_HANDLE;
    if (messenger_) {
        auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
        if (destroy) destroy(instance_, messenger_, nullptr);
        messenger_ = VK_NULL_HANDLE;
    }
    if (instance_) vkDestroyInstance(instance_, nullptr);
    instance_ = VK_NULL_HANDLE;
}

uint32_t Context::memory_type(uint32_t type_bits, VkMemoryPropertyFlags required,
                              VkMemoryPropertyFlags preferred) const {
    int fallback = -1;
    for (uint32_t i = 0; i < memory_props_.memoryTypeCount; ++i) {
        if (!(type_bits & (1u << i))) continue;
        VkMemoryPropertyFlags f = memory_props_.memoryTypes[i].propertyFlags;
        if ((f & required) != required) continue;
        if ((f & preferred) == preferred) return i;
        if (fallback < 0) fallback = int(i);
    }
    if (fallback < 0) throw Error("Vulkan: no memory type with the required properties");
    return uint32_t(fallback);
}

void Context::on_validation_message(const ValidationMessage& m) {
    std::lock_guard<std::mutex> lock(messages_mutex_);
    messages_.push_back(m);
}

std::vector<ValidationMessage> Context::take_validation_messages() {
    std::lock_guard<std::mutex> lock(messages_mutex_);
    return std::exchange(messages_, {});
}

size_t Context::validation_message_count() const {
    std::lock_guard<std::mutex> lock(messages_mutex_);
    return messages_.size();
}

}  // namespace vtloc::rt
