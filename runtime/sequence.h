#pragma once
// One command buffer recording a whole graph: copies and dispatches, with
// pipeline barriers inserted automatically where two commands touch
// overlapping bytes and at least one writes (RAW, WAR, WAW) — and only there.
// Recorded once, submitted any number of times.
#include <vulkan/vulkan.h>

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/handle.h"
#include "runtime/memory.h"

namespace vtloc::rt {

class Context;
struct Pipeline;

enum class Access : uint8_t { Read = 1, Write = 2, ReadWrite = 3 };

struct Binding {
    BufferView view;
    Access access = Access::Read;
    // For a texel binding (PipelineDesc::texel_bindings): R32_SFLOAT or
    // R32G32B32A32_SFLOAT, the element the shader's texelFetch returns.
    VkFormat texel_format = VK_FORMAT_UNDEFINED;
};

class Sequence {
public:
    explicit Sequence(Context& ctx, bool profile = false);
    ~Sequence();
    Sequence(const Sequence&) = delete;
    Sequence& operator=(const Sequence&) = delete;

    void begin();  // (re)starts recording; forgets earlier commands
    void copy(const BufferView& src, const BufferView& dst);
    void dispatch(const Pipeline& p, const std::vector<Binding>& bindings, const void* push,
                  uint32_t push_bytes, uint32_t gx, uint32_t gy = 1, uint32_t gz = 1);
    // Timestamps around a group of commands (a graph node) when profiling.
    void begin_node(const std::string& label);
    void end_node();
    void end();  // closes recording; writes become visible to the host
    void submit_and_wait();

    bool profiling() const { return profile_; }
    uint32_t barrier_count() const { return barriers_; }
    uint32_t dispatch_count() const { return dispatches_; }

    struct NodeTime {
        std::string label;
        double ms = 0.0;
    };
    // GPU time per node of the last submit (empty unless profiling).
    std::vector<NodeTime> node_times() const;

    // Every dispatch recorded since begin(), in order, with the node it belongs
    // to (its begin_node label, "" outside a node): the shader, its
    // specialization constants and workgroup counts (what `vtloc check` reports).
    struct DispatchRecord {
        std::string node;
        std::string shader;
        std::vector<uint32_t> spec;
        uint32_t texel_bindings = 0;
        uint32_t groups[3] = {1, 1, 1};
    };
    const std::vector<DispatchRecord>& dispatch_log() const { return dispatch_log_; }

private:
    struct Range {
        VkBuffer buffer;
        VkDeviceSize begin, end;
        bool overlaps(const Range& o) const {
            return buffer == o.buffer && begin < o.end && o.begin < end;
        }
    };
    void track(const std::vector<std::pair<BufferView, Access>>& accesses,
               VkPipelineStageFlags stage);
    void barrier(VkPipelineStageFlags dst_stage, VkAccessFlags dst_access);
    VkDescriptorSet allocate_set(const Pipeline& p);
    // A texel binding's range in bytes, checked against the device's limits (names the binding).
    VkDeviceSize texel_range(const Pipeline& p, uint32_t index, const Binding& b) const;
    VkBufferView texel_view(const Binding& b, VkDeviceSize range);
    void timestamp();
    void check_recording(const char* what) const;

    Context& ctx_;
    bool profile_;
    bool recording_ = false;
    bool ended_ = false;
    CommandPoolHandle pool_;
    VkCommandBuffer cmd_ = VK_NULL_HANDLE;
    FenceHandle fence_;
    std::vector<DescriptorPoolHandle> descriptor_pools_;
    std::vector<BufferViewHandle> texel_views_;  // live until the next begin()
    size_t pools_used_ = 0;

    // Hazard tracking: what commands since the last barrier read and wrote.
    std::vector<Range> pending_reads_, pending_writes_;
    VkPipelineStageFlags pending_stages_ = 0;
    VkAccessFlags pending_write_access_ = 0;
    uint32_t barriers_ = 0;
    uint32_t dispatches_ = 0;

    // Profiling: two timestamps per node, in pools of kQueriesPerPool.
    static constexpr uint32_t kQueriesPerPool = 512;
    std::vector<QueryPoolHandle> query_pools_;
    uint32_t queries_used_ = 0;
    std::vector<std::string> node_labels_;
    bool in_node_ = false;
    std::string current_node_;
    std::vector<DispatchRecord> dispatch_log_;
};

}  // namespace vtloc::rt
