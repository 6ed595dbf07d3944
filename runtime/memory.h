#pragma once
// Device memory: whole VkBuffers (one allocation each, made rarely) and views
// into them. Tensors never own memory; they are views into an arena or the
// weights buffers, so a run allocates nothing.
#include <vulkan/vulkan.h>

#include <utility>

#include "runtime/handle.h"

#include <cstdint>
#include <vector>

namespace vtloc::rt {

class Context;

enum class MemoryKind {
    Device,   // storage + transfer, device-local where the device has it
    Staging,  // host-visible, host-coherent, mapped; for upload/download
};

class Buffer {
public:
    Buffer() = default;
    Buffer(Context& ctx, VkDeviceSize size, MemoryKind kind);
    Buffer(Buffer&& o) noexcept { *this = std::move(o); }
    Buffer& operator=(Buffer&& o) noexcept {
        if (this == &o) return *this;
        unreserve();
        buffer_ = std::move(o.buffer_);  // the buffer goes before its memory
        memory_ = std::move(o.memory_);
        ctx_ = std::exchange(o.ctx_, nullptr);
        reserved_ = std::exchange(o.reserved_, 0);
        size_ = std::exchange(o.size_, 0);
        mapped_ = std::exchange(o.mapped_, nullptr);
        return *this;
    }

    ~Buffer() { unreserve(); }
    VkBuffer handle() const { return buffer_.get(); }
    VkDeviceSize size() const { return size_; }
    // Non-null for staging buffers (persistently mapped).
    void* mapped() const { return mapped_; }

private:
    // The memory outlives the buffer bound to it (members go in reverse order);
    // freeing it unmaps it.
    void unreserve();
    MemoryHandle memory_;
    BufferHandle buffer_;
    Context* ctx_ = nullptr;  // whose memory budget holds reserved_ bytes
    uint64_t reserved_ = 0;
    VkDeviceSize size_ = 0;
    void* mapped_ = nullptr;
};

// A byte range of a buffer: what a shader binding sees.
struct BufferView {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceSize offset = 0;
    VkDeviceSize size = 0;
};

inline VkDeviceSize align_up(VkDeviceSize v, VkDeviceSize a) { return (v + a - 1) / a * a; }

// Packs many ranges into as few buffers as possible, each no larger than
// `max_chunk` (the device's maxStorageBufferRange), so that every range can be
// bound whole. Reserve all ranges first, then allocate() once.
class ChunkedBuffers {
public:
    struct Slot {
        uint32_t chunk = 0;
        VkDeviceSize offset = 0;
        VkDeviceSize size = 0;
    };
    ChunkedBuffers(VkDeviceSize max_chunk, VkDeviceSize alignment)
        : max_chunk_(max_chunk), alignment_(alignment) {}

    Slot reserve(VkDeviceSize size);  // throws if one range exceeds max_chunk
    void allocate(Context& ctx, MemoryKind kind);
    BufferView view(const Slot& s) const;
    const Buffer& chunk(uint32_t i) const { return buffers_[i]; }
    size_t chunk_count() const { return sizes_.size(); }
    VkDeviceSize total_bytes() const;

private:
    VkDeviceSize max_chunk_;
    VkDeviceSize alignment_;
    std::vector<VkDeviceSize> sizes_;
    std::vector<Buffer> buffers_;
};

}  // namespace vtloc::rt
