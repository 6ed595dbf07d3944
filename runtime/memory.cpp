#include "runtime/memory.h"

#include <string>
#include <utility>

#include "base/error.h"
#include "runtime/context.h"

namespace vtloc::rt {

Buffer::Buffer(Context& ctx, VkDeviceSize size, MemoryKind kind) {
    VkDevice dev = ctx.device();
    size_ = size < 16 ? 16 : size;  // zero-sized buffers are invalid; keep bindings legal
    VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.size = size_;
    bi.usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    if (kind == MemoryKind::Device)
        bi.usage |= VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT |
                    VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT;
    bi.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    check_vk(vkCreateBuffer(dev, &bi, nullptr, buffer_.out(dev)), "vkCreateBuffer");

    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(dev, buffer_.get(), &req);
    VkMemoryPropertyFlags required =
        kind == MemoryKind::Staging
            ? VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
            : 0;
    VkMemoryPropertyFlags preferred =
        kind == MemoryKind::Staging ? VK_MEMORY_PROPERTY_HOST_CACHED_BIT
                                    : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = ctx.memory_type(req.memoryTypeBits, required, preferred);
    ctx.reserve_memory(req.size);  // throws past the context's budget; released with the buffer
    ctx_ = &ctx;
    reserved_ = req.size;
    VkResult r = vkAllocateMemory(dev, &ai, nullptr, memory_.out(dev));
    if (r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY)
        throw Error("out of memory allocating a " + std::to_string(size_ >> 20) + " MiB Vulkan buffer");
    check_vk(r, "vkAllocateMemory");
    check_vk(vkBindBufferMemory(dev, buffer_.get(), memory_.get(), 0), "vkBindBufferMemory");
    if (kind == MemoryKind::Staging)
        check_vk(vkMapMemory(dev, memory_.get(), 0, VK_WHOLE_SIZE, 0, &mapped_), "vkMapMemory");
}

void Buffer::unreserve() {
    if (ctx_) ctx_->release_memory(reserved_);
    ctx_ = nullptr;
    reserved_ = 0;
}

ChunkedBuffers::Slot ChunkedBuffers::reserve(VkDeviceSize size) {
    if (size > max_chunk_)
        throw Error("a tensor of " + std::to_string(size) +
                    " bytes exceeds the device's maxStorageBufferRange (" +
                    std::to_string(max_chunk_) + " bytes)");
    if (sizes_.empty() || align_up(sizes_.back(), alignment_) + size > max_chunk_)
        sizes_.push_back(0);
    Slot s;
    s.chunk = uint32_t(sizes_.size() - 1);
    s.offset = align_up(sizes_.back(), alignment_);
    s.size = size;
    sizes_.back() = s.offset + size;
    return s;
}

void ChunkedBuffers::allocate(Context& ctx, MemoryKind kind) {
    buffers_.clear();
    for (VkDeviceSize s : sizes_) buffers_.emplace_back(ctx, s, kind);
}

BufferView ChunkedBuffers::view(const Slot& s) const {
    return BufferView{buffers_.at(s.chunk).handle(), s.offset, s.size};
}

VkDeviceSize ChunkedBuffers::total_bytes() const {
    VkDeviceSize t = 0;
    for (VkDeviceSize s : sizes_) t += s;
    return t;
}

}  // namespace vtloc::rt
