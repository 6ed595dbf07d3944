#include "engine/resident_weights.h"

#include <algorithm>
#include <cstring>

#include "base/error.h"
#include "runtime/context.h"
#include "runtime/sequence.h"

namespace vtloc {

ResidentWeights::ResidentWeights(rt::Context& ctx) : ctx_(ctx), align_(ctx.info().tensor_alignment()) {}

ResidentWeights::~ResidentWeights() = default;

size_t ResidentWeights::ensure(const Graph& g, const WeightStore& weights) {
    // Held through the upload: a second caller waits for the names rather than uploading them twice.
    std::lock_guard<std::mutex> lock(mutex_);
    struct Fresh {
        std::string name;
        const HostTensor* t;
        Shape shape;  // as the graph reads it
    };
    std::vector<Fresh> fresh;
    for (const Value& v : g.values()) {
        if (v.kind != ValueKind::Weight) continue;
        auto it = slots_.find(v.name);
        if (it != slots_.end()) {
            if (it->second.shape != v.shape)
                throw Error("weight '" + v.name + "' is resident as " + shape_str(it->second.shape) +
                            " but this graph reads it as " + shape_str(v.shape));
            batches_[it->second.batch].shared = true;
            continue;
        }
        if (std::any_of(fresh.begin(), fresh.end(), [&](const Fresh& f) { return f.name == v.name; })) continue;
        fresh.push_back({v.name, &weights.get(v.name, v.shape), v.shape});
    }
    if (fresh.empty()) return kNone;

    // Packed into as few immutable buffers as the binding range allows.
    auto bufs = std::make_unique<rt::ChunkedBuffers>(
        std::min<uint64_t>(ctx_.info().max_storage_buffer_range, 1ull << 30), align_);
    std::vector<rt::ChunkedBuffers::Slot> placed;
    for (const Fresh& f : fresh) placed.push_back(bufs->reserve(std::max<uint64_t>(4, f.t->data.size() * 4)));
    bufs->allocate(ctx_, rt::MemoryKind::Device);

    rt::Buffer staging(ctx_, bufs->total_bytes() + fresh.size() * align_, rt::MemoryKind::Staging);
    rt::Sequence seq(ctx_, false);
    seq.begin();
    uint64_t at = 0;
    for (size_t i = 0; i < fresh.size(); ++i) {
        const HostTensor& t = *fresh[i].t;
        rt::BufferView dst = bufs->view(placed[i]);
        if (!t.data.empty()) std::memcpy(static_cast<char*>(staging.mapped()) + at, t.data.data(), t.data.size() * 4);
        seq.copy({staging.handle(), at, dst.size}, dst);
        at += dst.size;
    }
    seq.end();
    seq.submit_and_wait();
    // Only now, with the upload done, do the names become visible.
    const size_t batch = batches_.size();
    batches_.push_back(Batch{std::move(bufs), false});
    for (size_t i = 0; i < fresh.size(); ++i)
        slots_[fresh[i].name] = Slot{batch, placed[i], fresh[i].shape};
    return batch;
}

rt::BufferView ResidentWeights::view(const std::string& name) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = slots_.find(name);
    if (it == slots_.end()) throw Error("weight '" + name + "' is not resident on the device");
    return batches_[it->second.batch].buffers->view(it->second.slot);
}

bool ResidentWeights::has(const std::string& name) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return slots_.count(name) != 0;
}

size_t ResidentWeights::count() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return slots_.size();
}

void ResidentWeights::forget(size_t batch) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (batch >= batches_.size() || batches_[batch].shared || !batches_[batch].buffers) return;
    for (auto it = slots_.begin(); it != slots_.end();) it = it->second.batch == batch ? slots_.erase(it) : std::next(it);
    batches_[batch].buffers.reset();
}

uint64_t ResidentWeights::bytes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    uint64_t n = 0;
    for (const auto& b : batches_)
        if (b.buffers) n += b.buffers->total_bytes();
    return n;
}

}  // namespace vtloc
