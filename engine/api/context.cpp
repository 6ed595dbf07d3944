// Devices and contexts of the public API.
#include <algorithm>

#include "engine/api/api_internal.h"
#include "runtime/device_profile.h"

#ifndef VTLOC_VERSION
#define VTLOC_VERSION "unknown"
#endif

namespace vtloc::api {

const char* version() { return VTLOC_VERSION; }

std::string one_line(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    std::string out;
    for (size_t i = 0; i < s.size(); ++i) {
        if (s[i] != '\n') {
            out += s[i];
            continue;
        }
        while (i + 1 < s.size() && s[i + 1] == ' ') ++i;  // indentation of the next line
        out += !out.empty() && out.back() == ':' ? " " : "; ";  // "devices:\n  0: x\n  1: y" -> "devices: 0: x; 1: y"
    }
    return out;
}

DeviceInfo to_api(const rt::DeviceInfo& d) {
    DeviceInfo o;
    o.index = int(d.index);
    o.name = d.name;
    o.type = rt::device_type_name(d.type);
    o.api_major = int(VK_API_VERSION_MAJOR(d.api_version));
    o.api_minor = int(VK_API_VERSION_MINOR(d.api_version));
    o.subgroup_size = d.subgroup_size;
    o.shared_memory_bytes = d.max_shared_memory;
    o.max_workgroup_invocations = d.max_invocations;
    o.max_workgroup_size = d.max_workgroup_size;
    o.max_workgroup_count = d.max_workgroup_count;
    o.max_storage_buffer_bytes = d.max_storage_buffer_range;
    o.max_storage_buffers = d.max_storage_buffers;
    o.max_push_constant_bytes = d.max_push_constants;
    o.max_texel_buffer_elements = d.max_texel_elements;
    o.timestamps = d.has_timestamps;
    o.device_local_bytes = d.device_local_bytes;
    o.host_vector_registers = d.host_vector_registers;
    o.compute_units = d.compute_units;
    return o;
}

std::string device_profile(int index) {
    return guarded([&] {
        for (const rt::DeviceInfo& d : rt::Context::list_devices())
            if (int(d.index) == index) return rt::device_profile_json(d);
        throw Error("no Vulkan device with index " + std::to_string(index));
    });
}

std::vector<DeviceInfo> list_devices() {
    return guarded([] {
        std::vector<DeviceInfo> out;
        for (const rt::DeviceInfo& d : rt::Context::list_devices())
            if (d.has_compute_queue) out.push_back(to_api(d));
        return out;
    });
}

Context::Context(const ContextOptions& options) {
    impl_ = guarded([&] {
        rt::ContextOptions o;
        o.device = options.device;
        o.validation = options.validation == Validation::Environment ? -1 : options.validation == Validation::On ? 1 : 0;
        o.memory_budget = options.memory_budget;
        auto impl = std::make_unique<Impl>(o);
        impl->device = to_api(impl->ctx.info());
        return impl;
    });
}

Context::~Context() = default;
Context::Context(Context&&) noexcept = default;
Context& Context::operator=(Context&&) noexcept = default;

const DeviceInfo& Context::device() const { return impl_->device; }

bool Context::validation_enabled() const { return impl_->ctx.validation_enabled(); }

uint64_t Context::memory_in_use() const { return impl_->ctx.memory_in_use(); }

void testing::simulate_device_loss(Context& c) { ContextAccess::rt(c).simulate_device_loss(); }

std::vector<std::string> Context::take_validation_messages() {
    std::vector<std::string> out;
    for (const rt::ValidationMessage& m : impl_->ctx.take_validation_messages())
        out.push_back(m.severity + ": " + one_line(m.text));
    return out;
}

}  // namespace vtloc::api
