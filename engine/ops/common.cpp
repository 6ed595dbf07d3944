#include "engine/ops/common.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.h"

namespace vtloc::ops {

float apply_act(float v, uint32_t act, float slope) {
    switch (act) {
        case kActRelu: return v > 0.0f ? v : 0.0f;
        case kActLeaky: return v >= 0.0f ? v : v * slope;
        case kActTanh: return std::tanh(v);
        case kActSigmoid: return float(1.0 / (1.0 + std::exp(-double(v))));
        default: return v;
    }
}

uint32_t elementwise_local_size(const rt::DeviceInfo& d) {
    uint32_t limit = std::min({256u, d.max_invocations, d.max_workgroup_size[0]});
    uint32_t sg = std::max(1u, d.subgroup_size);
    return limit >= sg ? limit / sg * sg : limit;
}

bool has_subgroup_shuffles(const rt::DeviceInfo& d) {
    return (d.subgroup_ops & VK_SUBGROUP_FEATURE_SHUFFLE_BIT) && (d.subgroup_ops & VK_SUBGROUP_FEATURE_BASIC_BIT) &&
           d.subgroup_size > 0 && d.subgroup_size <= elementwise_local_size(d);
}

bool shuffles_allowed(const GpuOpArgs& a) {
    return a.params.get("subgroup", 1) != 0 && has_subgroup_shuffles(a.ctx.info());
}

bool texels_allowed(const GpuOpArgs& a, std::initializer_list<uint64_t> texels) {
    if (a.params.get("texel", 1) == 0) return false;
    for (uint64_t n : texels)
        if (n > a.ctx.info().max_texel_elements) return false;
    return true;
}

uint32_t fill_local_size(const rt::DeviceInfo& d, uint64_t items) {
    const uint32_t sg = std::max(1u, d.subgroup_size);
    uint32_t local = elementwise_local_size(d);
    while (local / 2 >= sg && local / 2 % sg == 0 && (items + local - 1) / local < rt::fill_workgroups(d)) local /= 2;
    return local;
}

uint32_t row_local_size(const rt::DeviceInfo& d, uint64_t rows) {
    const uint32_t sg = std::max(1u, d.subgroup_size);
    uint32_t local = elementwise_local_size(d);
    while (local > sg && rows < 16ull * local) local = std::max(sg, local / 2 / sg * sg);
    return local;
}

uint32_t row_span_local_size(const rt::DeviceInfo& d, uint64_t n) {
    const uint64_t sg = std::max(1u, d.subgroup_size);
    return uint32_t(std::min<uint64_t>(elementwise_local_size(d), std::max(sg, (n + sg - 1) / sg * sg)));
}

uint32_t subgroup_group_size(const rt::DeviceInfo& d) {
    const uint32_t sg = std::max(1u, d.subgroup_size);
    return std::max(sg, std::min(64u, elementwise_local_size(d)) / sg * sg);
}

uint32_t answers_per_shuffle(const rt::DeviceInfo& d) { return d.type == VK_PHYSICAL_DEVICE_TYPE_CPU ? 4 : 1; }

void check_loop_budget(const rt::DeviceInfo& d, uint64_t iterations, const std::string& what) {
    if (d.type == VK_PHYSICAL_DEVICE_TYPE_CPU && iterations > kLoopIterationBudget)
        throw Error(what + " would loop up to " + std::to_string(iterations) + " times in one invocation; '" + d.name +
                    "' is a CPU driver, which ends a shader's loops after 65,535 iterations (limit used: " +
                    std::to_string(kLoopIterationBudget) + "): reduce the cloud first");
}

uint32_t grid_groups(uint64_t n, uint32_t local_size, const rt::DeviceInfo& d) {
    uint64_t groups = (n + local_size - 1) / local_size;
    // Beyond a few thousand groups a grid-stride loop costs nothing and keeps
    // every size within maxComputeWorkGroupCount.
    uint64_t cap = std::min<uint64_t>(d.max_workgroup_count[0], 4096);
    return uint32_t(std::clamp<uint64_t>(groups, 1, cap));
}

const rt::Pipeline& pipeline(rt::Context& ctx, const char* shader, uint32_t bindings,
                             uint32_t push_bytes, std::vector<uint32_t> spec) {
    return ctx.pipelines().get(rt::PipelineDesc{shader, bindings, push_bytes, std::move(spec)});
}

uint32_t to_u32(int64_t v, const char* what) {
    if (v < 0 || v > int64_t(std::numeric_limits<uint32_t>::max()))
        throw Error(std::string(what) + " (" + std::to_string(v) + ") does not fit 32-bit shader indexing");
    return uint32_t(v);
}

void expect_input_count(const std::vector<TensorDesc>& in, size_t lo, size_t hi) {
    if (in.size() < lo || in.size() > hi)
        throw Error("takes " + (lo == hi ? std::to_string(lo) : std::to_string(lo) + ".." + std::to_string(hi)) +
                    " inputs, got " + std::to_string(in.size()));
}

void expect_f32(const std::vector<TensorDesc>& in) {
    for (size_t i = 0; i < in.size(); ++i)
        if (in[i].type != ElemType::F32)
            throw Error("input " + std::to_string(i) + " is " + elem_type_name(in[i].type) + ", expected F32");
}

}  // namespace vtloc::ops
