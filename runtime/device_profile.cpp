#include "runtime/device_profile.h"

#include <fstream>
#include <limits>
#include <sstream>
#include <utility>

#include <nlohmann/json.hpp>

#include "base/error.h"

namespace vtloc::rt {

namespace {

using nlohmann::json;

const std::pair<const char*, VkPhysicalDeviceType> kTypes[] = {
    {"discrete GPU", VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU},
    {"integrated GPU", VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU},
    {"virtual GPU", VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU},
    {"CPU", VK_PHYSICAL_DEVICE_TYPE_CPU},
};

const std::pair<const char*, uint32_t> kSubgroupOps[] = {
    {"basic", VK_SUBGROUP_FEATURE_BASIC_BIT},       {"vote", VK_SUBGROUP_FEATURE_VOTE_BIT},
    {"arithmetic", VK_SUBGROUP_FEATURE_ARITHMETIC_BIT}, {"ballot", VK_SUBGROUP_FEATURE_BALLOT_BIT},
    {"shuffle", VK_SUBGROUP_FEATURE_SHUFFLE_BIT},   {"shuffle_relative", VK_SUBGROUP_FEATURE_SHUFFLE_RELATIVE_BIT},
    {"clustered", VK_SUBGROUP_FEATURE_CLUSTERED_BIT}, {"quad", VK_SUBGROUP_FEATURE_QUAD_BIT},
};

struct Reader {
    const json& j;
    const std::string& source;
    [[noreturn]] void fail(const std::string& field, const std::string& why) const {
        throw Error(source + ": device profile field '" + field + "' " + why);
    }
    const json& at(const char* field) const {
        if (!j.contains(field)) fail(field, "is missing");
        return j.at(field);
    }
    uint64_t uint(const json& v, const std::string& field, uint64_t lo, uint64_t hi) const {
        if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<int64_t>() >= 0))
            fail(field, "must be a whole number >= 0");
        const uint64_t x = v.get<uint64_t>();
        if (x < lo || x > hi) fail(field, "is " + std::to_string(x) + ", outside " + std::to_string(lo) + ".." + std::to_string(hi));
        return x;
    }
    uint64_t uint(const char* field, uint64_t lo = 0, uint64_t hi = std::numeric_limits<uint32_t>::max()) const {
        return uint(at(field), field, lo, hi);
    }
    uint64_t power_of_two(const char* field) const {
        const uint64_t x = uint(field, 1, uint64_t(1) << 16);
        if (x & (x - 1)) fail(field, "must be a power of two");
        return x;
    }
    std::array<uint32_t, 3> triple(const char* field) const {
        const json& v = at(field);
        if (!v.is_array() || v.size() != 3) fail(field, "must be an array of 3 whole numbers");
        std::array<uint32_t, 3> out{};
        for (size_t i = 0; i < 3; ++i)
            out[i] = uint32_t(uint(v[i], std::string(field) + "[" + std::to_string(i) + "]", 1, std::numeric_limits<uint32_t>::max()));
        return out;
    }
};

}  // namespace

DeviceInfo parse_device_profile(const std::string& text, const std::string& source) {
    json j;
    try {
        j = json::parse(text);
    } catch (const json::exception& e) {
        throw Error(source + ": not a device profile (invalid JSON: " + e.what() + ")");
    }
    // value() would throw json's own error where "format" is not a string (found by fuzzing).
    if (!j.is_object() || !j.contains("format") || !j.at("format").is_string() ||
        j.at("format").get<std::string>() != "vtloc-device-profile/1")
        throw Error(source + ": not a device profile (needs \"format\": \"vtloc-device-profile/1\")");
    const Reader r{j, source};
    DeviceInfo d;
    if (!r.at("name").is_string() || r.at("name").get<std::string>().empty()) r.fail("name", "must be a non-empty string");
    d.name = r.at("name").get<std::string>();
    const json& type = r.at("type");
    bool known = false;
    for (const auto& [n, t] : kTypes)
        if (type.is_string() && type.get<std::string>() == n) d.type = t, known = true;
    if (!known) r.fail("type", "must be one of \"discrete GPU\", \"integrated GPU\", \"virtual GPU\", \"CPU\"");
    d.vendor_id = uint32_t(r.uint("vendor_id"));
    d.api_version = VK_API_VERSION_1_1;
    d.compute_units = uint32_t(r.uint("compute_units", 0, 1 << 16));
    d.subgroup_size = uint32_t(r.power_of_two("subgroup_size"));
    const json& ops = r.at("subgroup_ops");
    if (!ops.is_array()) r.fail("subgroup_ops", "must be an array of names");
    for (const json& o : ops) {
        uint32_t bit = 0;
        for (const auto& [n, b] : kSubgroupOps)
            if (o.is_string() && o.get<std::string>() == n) bit = b;
        if (!bit) r.fail("subgroup_ops", "holds " + o.dump() + "; known: basic, vote, arithmetic, ballot, shuffle, shuffle_relative, clustered, quad");
        d.subgroup_ops |= bit;
    }
    d.max_shared_memory = uint32_t(r.uint("max_shared_memory", 16384));  // Vulkan's minimum
    d.max_invocations = uint32_t(r.uint("max_invocations", 128));
    d.max_workgroup_size = r.triple("max_workgroup_size");
    d.max_workgroup_count = r.triple("max_workgroup_count");
    d.max_storage_buffer_range = r.uint("max_storage_buffer_range", 1 << 27, std::numeric_limits<uint64_t>::max());
    d.storage_offset_alignment = r.power_of_two("storage_offset_alignment");
    d.max_push_constants = uint32_t(r.uint("max_push_constants", 128));
    d.max_storage_buffers = uint32_t(r.uint("max_storage_buffers", 4));
    d.texel_offset_alignment = r.power_of_two("texel_offset_alignment");
    d.max_texel_elements = uint32_t(r.uint("max_texel_elements", 65536));
    d.uniform_offset_alignment = r.power_of_two("uniform_offset_alignment");
    d.max_uniform_range = r.uint("max_uniform_range", 16384);
    d.has_compute_queue = true;
    return d;
}

DeviceInfo read_device_profile(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path + ": cannot read the device profile");
    std::stringstream ss;
    ss << f.rdbuf();
    return parse_device_profile(ss.str(), path);
}

std::string device_profile_json(const DeviceInfo& d) {
    json ops = json::array();
    for (const auto& [n, b] : kSubgroupOps)
        if (d.subgroup_ops & b) ops.push_back(n);
    json j{{"format", "vtloc-device-profile/1"},
           {"name", d.name},
           {"type", device_type_name(d.type)},
           {"vendor_id", d.vendor_id},
           {"compute_units", d.compute_units},
           {"subgroup_size", d.subgroup_size},
           {"subgroup_ops", ops},
           {"max_shared_memory", d.max_shared_memory},
           {"max_invocations", d.max_invocations},
           {"max_workgroup_size", d.max_workgroup_size},
           {"max_workgroup_count", d.max_workgroup_count},
           {"max_storage_buffer_range", d.max_storage_buffer_range},
           {"storage_offset_alignment", d.storage_offset_alignment},
           {"max_push_constants", d.max_push_constants},
           {"max_storage_buffers", d.max_storage_buffers},
           {"texel_offset_alignment", d.texel_offset_alignment},
           {"max_texel_elements", d.max_texel_elements},
           {"uniform_offset_alignment", d.uniform_offset_alignment},
           {"max_uniform_range", d.max_uniform_range}};
    return j.dump(1) + "\n";
}

}  // namespace vtloc::rt
