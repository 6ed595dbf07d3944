#include "runtime/sequence.h"

#include "base/error.h"
#include "runtime/context.h"
#include "runtime/pipeline.h"

namespace vtloc::rt {

namespace {
constexpr uint32_t kSetsPerPool = 128;
constexpr uint32_t kDescriptorsPerPool = 1024;
constexpr uint64_t kSubmitTimeoutNs = 600ull * 1000 * 1000 * 1000;  // 10 min: report, never hang
}  // namespace

Sequence::Sequence(Context& ctx, bool profile) : ctx_(ctx), profile_(profile) {
    if (profile_ && !ctx_.info().has_timestamps)
        profile_ = false;  // the queue has no timestamps: profiling is silently unavailable
    VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pi.queueFamilyIndex = ctx_.queue_family();
    check_vk(vkCreateCommandPool(ctx_.device(), &pi, nullptr, pool_.out(ctx_.device())), "vkCreateCommandPool");
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = pool_.get();
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    check_vk(vkAllocateCommandBuffers(ctx_.device(), &ai, &cmd_), "vkAllocateCommandBuffers");
    check_vk(vkCreateFence(ctx_.device(), &fi, nullptr, fence_.out(ctx_.device())), "vkCreateFence");
}

Sequence::~Sequence() = default;

void Sequence::check_recording(const char* what) const {
    if (!recording_) throw Error(std::string("Sequence::") + what + " outside begin()/end()");
}

void Sequence::begin() {
    ctx_.check_not_lost();
    check_vk(vkResetCommandBuffer(cmd_, 0), "vkResetCommandBuffer");
    for (auto& p : descriptor_pools_) vkResetDescriptorPool(ctx_.device(), p.get(), 0);
    pools_used_ = 0;
    texel_views_.clear();
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    check_vk(vkBeginCommandBuffer(cmd_, &bi), "vkBeginCommandBuffer");
    recording_ = true;
    ended_ = false;
    pending_reads_.clear();
    pending_writes_.clear();
    pending_stages_ = 0;
    pending_write_access_ = 0;
    barriers_ = 0;
    dispatches_ = 0;
    queries_used_ = 0;
    node_labels_.clear();
    in_node_ = false;
    current_node_.clear();
    dispatch_log_.clear();
}

void Sequence::barrier(VkPipelineStageFlags dst_stage, VkAccessFlags dst_access) {
    VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = pending_write_access_;
    mb.dstAccessMask = dst_access;
    vkCmdPipelineBarrier(cmd_, pending_stages_ ? pending_stages_ : VkPipelineStageFlags(VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT),
                         dst_stage, 0, 1, &mb, 0, nullptr, 0, nullptr);
    ++barriers_;
    pending_reads_.clear();
    pending_writes_.clear();
    pending_stages_ = 0;
    pending_write_access_ = 0;
}

void Sequence::track(const std::vector<std::pair<BufferView, Access>>& accesses,
                     VkPipelineStageFlags stage) {
    bool hazard = false;
    for (auto& [view, access] : accesses) {
        Range r{view.buffer, view.offset, view.offset + view.size};
        bool writes = uint8_t(access) & uint8_t(Access::Write);
        for (auto& w : pending_writes_) hazard |= r.overlaps(w);           // RAW, WAW
        if (writes)
            for (auto& rd : pending_reads_) hazard |= r.overlaps(rd);      // WAR
    }
    if (hazard) {
        // Whatever comes next (compute or transfer) is ordered after everything
        // before the barrier, so all pending ranges can be forgotten.
        barrier(VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_UNIFORM_READ_BIT |
                    VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
    }
    for (auto& [view, access] : accesses) {
        Range r{view.buffer, view.offset, view.offset + view.size};
        if (uint8_t(access) & uint8_t(Access::Read)) pending_reads_.push_back(r);
        if (uint8_t(access) & uint8_t(Access::Write)) {
            pending_writes_.push_back(r);
            pending_write_access_ |= stage == VK_PIPELINE_STAGE_TRANSFER_BIT
                                         ? VK_ACCESS_TRANSFER_WRITE_BIT
                                         : VK_ACCESS_SHADER_WRITE_BIT;
        }
    }
    pending_stages_ |= stage;
}

void Sequence::copy(const BufferView& src, const BufferView& dst) {
    check_recording("copy");
    if (src.size != dst.size)
        throw Error("Sequence::copy: source and destination sizes differ");
    if (src.size == 0) return;
    track({{src, Access::Read}, {dst, Access::Write}}, VK_PIPELINE_STAGE_TRANSFER_BIT);
    VkBufferCopy region{src.offset, dst.offset, src.size};
    vkCmdCopyBuffer(cmd_, src.buffer, dst.buffer, 1, &region);
}

VkDescriptorSet Sequence::allocate_set(const Pipeline& p) {
    VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    ai.descriptorSetCount = 1;
    ai.pSetLayouts = p.set_layout.ptr();
    VkDescriptorSet set = VK_NULL_HANDLE;
    while (true) {
        if (pools_used_ == descriptor_pools_.size()) {
            const uint32_t n = std::max(kDescriptorsPerPool, p.desc.bindings);
            VkDescriptorPoolSize sizes[3] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, n},
                                             {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, n},
                                             {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, n}};
            VkDescriptorPoolCreateInfo pi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
            pi.maxSets = kSetsPerPool;
            pi.poolSizeCount = 3;
            pi.pPoolSizes = sizes;
            DescriptorPoolHandle pool;
            check_vk(vkCreateDescriptorPool(ctx_.device(), &pi, nullptr, pool.out(ctx_.device())),
                     "vkCreateDescriptorPool");
            descriptor_pools_.push_back(std::move(pool));
        }
        ai.descriptorPool = descriptor_pools_[pools_used_].get();
        VkResult r = vkAllocateDescriptorSets(ctx_.device(), &ai, &set);
        if (r == VK_SUCCESS) return set;
        if (r != VK_ERROR_OUT_OF_POOL_MEMORY && r != VK_ERROR_FRAGMENTED_POOL)
            check_vk(r, "vkAllocateDescriptorSets");
        ++pools_used_;  // this pool is full: move on to the next (or a new) one
    }
}

VkDeviceSize Sequence::texel_range(const Pipeline& p, uint32_t index, const Binding& b) const {
    const DeviceInfo& info = ctx_.info();
    const std::string what = "shader '" + p.desc.shader + "': texel binding " + std::to_string(index);
    // The formats every Vulkan device supports for uniform texel buffers.
    VkDeviceSize texel = b.texel_format == VK_FORMAT_R32_SFLOAT || b.texel_format == VK_FORMAT_R32_SINT ? 4
                         : b.texel_format == VK_FORMAT_R32G32B32A32_SFLOAT                             ? 16
                                                                                                       : 0;
    if (!texel) throw Error(what + " needs texel_format R32_SFLOAT, R32_SINT or R32G32B32A32_SFLOAT");
    if (b.access != Access::Read) throw Error(what + " is read-only");
    if (b.view.offset % info.texel_offset_alignment)
        throw Error(what + " is not aligned to minTexelBufferOffsetAlignment");
    VkDeviceSize range = b.view.size / texel * texel;  // whole texels only
    if (range == 0) throw Error(what + " is smaller than one texel");
    if (range / texel > info.max_texel_elements)
        throw Error(what + " has " + std::to_string(range / texel) + " texels; the device allows " +
                    std::to_string(info.max_texel_elements));
    return range;
}

VkBufferView Sequence::texel_view(const Binding& b, VkDeviceSize range) {
    VkBufferViewCreateInfo vi{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
    vi.buffer = b.view.buffer;
    vi.format = b.texel_format;
    vi.offset = b.view.offset;
    vi.range = range;
    BufferViewHandle view;
    check_vk(vkCreateBufferView(ctx_.device(), &vi, nullptr, view.out(ctx_.device())), "vkCreateBufferView");
    texel_views_.push_back(std::move(view));
    return texel_views_.back().get();
}

void Sequence::dispatch(const Pipeline& p, const std::vector<Binding>& bindings,
                        const void* push, uint32_t push_bytes, uint32_t gx, uint32_t gy,
                        uint32_t gz) {
    check_recording("dispatch");
    const DeviceInfo& info = ctx_.info();
    if (bindings.size() != p.desc.bindings)
        throw Error("shader '" + p.desc.shader + "' takes " + std::to_string(p.desc.bindings) +
                    " buffers, got " + std::to_string(bindings.size()));
    if (push_bytes != p.desc.push_bytes)
        throw Error("shader '" + p.desc.shader + "': push-constant size mismatch");
    if (gx == 0 || gy == 0 || gz == 0) return;  // empty tensor: nothing to do
    if (gx > info.max_workgroup_count[0] || gy > info.max_workgroup_count[1] ||
        gz > info.max_workgroup_count[2])
        throw Error("shader '" + p.desc.shader + "': dispatch of " + std::to_string(gx) + "x" +
                    std::to_string(gy) + "x" + std::to_string(gz) +
                    " workgroups exceeds the device's maxComputeWorkGroupCount");

    // Every binding is checked against the device's limits (a plan-only context's
    // profile's too); only a real device gets descriptors and commands.
    const bool plan = ctx_.plan_only();
    std::vector<std::pair<BufferView, Access>> accesses;
    std::vector<VkDescriptorBufferInfo> infos(bindings.size());
    std::vector<VkBufferView> views(bindings.size(), VK_NULL_HANDLE);
    std::vector<VkWriteDescriptorSet> writes(bindings.size());
    VkDescriptorSet set = plan ? VK_NULL_HANDLE : allocate_set(p);
    for (size_t i = 0; i < bindings.size(); ++i) {
        const BufferView& v = bindings[i].view;
        writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        writes[i].dstSet = set;
        writes[i].dstBinding = uint32_t(i);
        writes[i].descriptorCount = 1;
        accesses.push_back({v, bindings[i].access});
        if ((p.desc.texel_bindings >> i) & 1) {
            const VkDeviceSize range = texel_range(p, uint32_t(i), bindings[i]);
            if (!plan) views[i] = texel_view(bindings[i], range);
            writes[i].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
            writes[i].pTexelBufferView = &views[i];
            continue;
        }
        if ((p.desc.uniform_bindings >> i) & 1) {
            const std::string what = "shader '" + p.desc.shader + "': uniform binding " + std::to_string(i);
            if (bindings[i].access != Access::Read) throw Error(what + " is read-only");
            if (v.size > info.max_uniform_range)
                throw Error(what + " has " + std::to_string(v.size) + " bytes; the device allows " +
                            std::to_string(info.max_uniform_range) + " (maxUniformBufferRange)");
            if (v.offset % info.uniform_offset_alignment)
                throw Error(what + " is not aligned to minUniformBufferOffsetAlignment");
            infos[i] = {v.buffer, v.offset, v.size ? v.size : 16};
            writes[i].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
            writes[i].pBufferInfo = &infos[i];
            continue;
        }
        if (v.size > info.max_storage_buffer_range)
            throw Error("shader '" + p.desc.shader + "': binding " + std::to_string(i) +
                        " is larger than maxStorageBufferRange");
        if (v.offset % info.storage_offset_alignment)
            throw Error("shader '" + p.desc.shader + "': binding " + std::to_string(i) +
                        " is not aligned to minStorageBufferOffsetAlignment");
        infos[i] = {v.buffer, v.offset, v.size ? v.size : 4};
        writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        writes[i].pBufferInfo = &infos[i];
    }
    if (plan) {  // the profile's device: tracked (barriers) and logged, never recorded
        track(accesses, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);
        ++dispatches_;
        dispatch_log_.push_back({in_node_ ? current_node_ : std::string(), p.desc.shader, p.desc.spec,
                                 p.desc.texel_bindings, {gx, gy, gz}});
        return;
    }
    vkUpdateDescriptorSets(ctx_.device(), uint32_t(writes.size()), writes.data(), 0, nullptr);
    track(accesses, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);

    vkCmdBindPipeline(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, p.pipeline.get());
    vkCmdBindDescriptorSets(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, p.layout.get(), 0, 1, &set, 0, nullptr);
    if (push_bytes)
        vkCmdPushConstants(cmd_, p.layout.get(), VK_SHADER_STAGE_COMPUTE_BIT, 0, push_bytes, push);
    vkCmdDispatch(cmd_, gx, gy, gz);
    ++dispatches_;
    dispatch_log_.push_back({in_node_ ? current_node_ : std::string(), p.desc.shader, p.desc.spec,
                             p.desc.texel_bindings, {gx, gy, gz}});
}

void Sequence::timestamp() {
    uint32_t pool_index = queries_used_ / kQueriesPerPool;
    if (pool_index == query_pools_.size()) {
        VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
        qi.queryType = VK_QUERY_TYPE_TIMESTAMP;
        qi.queryCount = kQueriesPerPool;
        QueryPoolHandle qp;
        check_vk(vkCreateQueryPool(ctx_.device(), &qi, nullptr, qp.out(ctx_.device())), "vkCreateQueryPool");
        query_pools_.push_back(std::move(qp));
    }
    uint32_t q = queries_used_ % kQueriesPerPool;
    if (q == 0) vkCmdResetQueryPool(cmd_, query_pools_[pool_index].get(), 0, kQueriesPerPool);
    vkCmdWriteTimestamp(cmd_, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, query_pools_[pool_index].get(), q);
    ++queries_used_;
}

void Sequence::begin_node(const std::string& label) {
    check_recording("begin_node");
    if (in_node_) throw Error("Sequence::begin_node: nodes do not nest");
    in_node_ = true;
    current_node_ = label;
    if (!profile_) return;
    node_labels_.push_back(label);
    timestamp();
}

void Sequence::end_node() {
    check_recording("end_node");
    if (!in_node_) throw Error("Sequence::end_node without begin_node");
    in_node_ = false;
    if (profile_) timestamp();
}

void Sequence::end() {
    check_recording("end");
    if (pending_stages_) barrier(VK_PIPELINE_STAGE_HOST_BIT, VK_ACCESS_HOST_READ_BIT);
    check_vk(vkEndCommandBuffer(cmd_), "vkEndCommandBuffer");
    recording_ = false;
    ended_ = true;
}

void Sequence::submit_and_wait() {
    if (!ended_) throw Error("Sequence::submit_and_wait before end()");
    if (ctx_.plan_only() && dispatches_ > 0)
        throw Error("this context plans for the device profile '" + ctx_.info().name +
                    "': it records dispatches but never runs them");
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmd_;
    std::lock_guard<std::mutex> queue_lock(ctx_.queue_mutex());
    ctx_.check_not_lost();
    check_vk(vkResetFences(ctx_.device(), 1, fence_.ptr()), "vkResetFences");
    VkResult r = ctx_.take_simulated_loss() ? VK_ERROR_DEVICE_LOST : vkQueueSubmit(ctx_.queue(), 1, &si, fence_.get());
    if (r == VK_SUCCESS) r = vkWaitForFences(ctx_.device(), 1, fence_.ptr(), VK_TRUE, kSubmitTimeoutNs);
    if (r == VK_TIMEOUT) throw Error("GPU work did not finish within 10 minutes");
    if (r == VK_ERROR_DEVICE_LOST) {
        ctx_.mark_lost();
        throw Error("the GPU device was lost during a submit (VK_ERROR_DEVICE_LOST): a driver reset, a hang or a "
                    "removed GPU; this context refuses further work: create a new context");
    }
    check_vk(r, "vkQueueSubmit / vkWaitForFences");
}

std::vector<Sequence::NodeTime> Sequence::node_times() const {
    std::vector<NodeTime> out;
    if (!profile_ || queries_used_ == 0) return out;
    std::vector<uint64_t> ticks(queries_used_);
    for (size_t p = 0; p * kQueriesPerPool < queries_used_; ++p) {
        uint32_t n = std::min<uint32_t>(kQueriesPerPool, queries_used_ - uint32_t(p) * kQueriesPerPool);
        check_vk(vkGetQueryPoolResults(ctx_.device(), query_pools_[p].get(), 0, n, n * sizeof(uint64_t),
                                       ticks.data() + p * kQueriesPerPool, sizeof(uint64_t),
                                       VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
                 "vkGetQueryPoolResults");
    }
    double period = ctx_.info().timestamp_period;  // float ns per tick, kept fractional
    for (size_t i = 0; i < node_labels_.size(); ++i)
        out.push_back({node_labels_[i], double(ticks[2 * i + 1] - ticks[2 * i]) * period * 1e-6});
    return out;
}

}  // namespace vtloc::rt
