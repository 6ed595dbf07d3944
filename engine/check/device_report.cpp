#include "engine/check/device_report.h"

#include <cstring>

#include "runtime/context.h"

namespace vtloc::check {

namespace {

std::string version_str(uint32_t v) {
    return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
           std::to_string(VK_API_VERSION_PATCH(v));
}

// driverVersion is vendor-encoded; NVIDIA uses 10.8.8.6 bits, most others Vulkan's.
std::string driver_version_str(const rt::DeviceInfo& d) {
    const uint32_t v = d.driver_version;
    if (d.vendor_id == 0x10DE)
        return std::to_string(v >> 22) + "." + std::to_string((v >> 14) & 0xff) + "." + std::to_string((v >> 6) & 0xff);
    return version_str(v);
}

std::string driver_str(rt::Context& ctx) {
    const rt::DeviceInfo& d = ctx.info();
    std::string s = "driverVersion " + driver_version_str(d);
    if (!rt::has_device_extension(ctx.physical_device(), VK_KHR_DRIVER_PROPERTIES_EXTENSION_NAME)) return s;
    VkPhysicalDeviceDriverPropertiesKHR drv{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES_KHR};
    VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    p2.pNext = &drv;
    vkGetPhysicalDeviceProperties2(ctx.physical_device(), &p2);
    return std::string(drv.driverName) + " " + drv.driverInfo + " (" + s + ")";
}

}  // namespace

DeviceReport device_report(rt::Context& ctx) {
    const rt::DeviceInfo& d = ctx.info();
    DeviceReport r;
    r.name = d.name;
    r.type = rt::device_type_name(d.type);
    r.vulkan = version_str(d.api_version);
    r.driver = driver_str(ctx);
    auto xyz = [](const std::array<uint32_t, 3>& a) {
        return std::to_string(a[0]) + " x " + std::to_string(a[1]) + " x " + std::to_string(a[2]);
    };
    std::string ops;
    const std::pair<uint32_t, const char*> names[] = {
        {VK_SUBGROUP_FEATURE_BASIC_BIT, "basic"},       {VK_SUBGROUP_FEATURE_VOTE_BIT, "vote"},
        {VK_SUBGROUP_FEATURE_ARITHMETIC_BIT, "arithmetic"}, {VK_SUBGROUP_FEATURE_BALLOT_BIT, "ballot"},
        {VK_SUBGROUP_FEATURE_SHUFFLE_BIT, "shuffle"},   {VK_SUBGROUP_FEATURE_SHUFFLE_RELATIVE_BIT, "shuffle_relative"},
        {VK_SUBGROUP_FEATURE_CLUSTERED_BIT, "clustered"}, {VK_SUBGROUP_FEATURE_QUAD_BIT, "quad"}};
    for (auto [bit, name] : names)
        if (d.subgroup_ops & bit) ops.append(ops.empty() ? "" : " ").append(name);
    r.limits = {{"subgroup size", std::to_string(d.subgroup_size)},
                {"subgroup ops (compute)", ops.empty() ? "none" : ops},
                {"max workgroup invocations", std::to_string(d.max_invocations)},
                {"max workgroup size", xyz(d.max_workgroup_size)},
                {"max workgroup count", xyz(d.max_workgroup_count)},
                {"shared memory per workgroup", std::to_string(d.max_shared_memory) + " bytes"},
                {"max storage buffer range", std::to_string(d.max_storage_buffer_range) + " bytes"},
                {"storage buffers per stage", std::to_string(d.max_storage_buffers)},
                {"max texel buffer elements", std::to_string(d.max_texel_elements)},
                {"push constants", std::to_string(d.max_push_constants) + " bytes"},
                {"timestamps", d.has_timestamps ? "yes" : "no"}};
    if (d.host_vector_registers > 0)  // CPU devices: lavapipe's speed depends on it
        r.limits.push_back({"host CPU vector registers", std::to_string(d.host_vector_registers)});
    return r;
}

}  // namespace vtloc::check
