#pragma once
// A model's weights on the device, each named tensor uploaded once and shared
// by every executor (graph shape) of that model on one context: a new shape
// (image size, batch, K, symmetry, profiling) adds only its activation arena
// and staging. Slots are immutable once written, so executors read them with
// no barrier beyond the upload's own wait. Trackers of one object share one too
// (track::Tracker's with_options form), possibly from several threads: every
// call takes the lock.
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "engine/graph.h"
#include "engine/weights.h"
#include "runtime/memory.h"

namespace vtloc {

namespace rt {
class Context;
}

class ResidentWeights {
public:
    explicit ResidentWeights(rt::Context& ctx);
    ~ResidentWeights();
    ResidentWeights(const ResidentWeights&) = delete;
    ResidentWeights& operator=(const ResidentWeights&) = delete;

    // Uploads the weights `g` reads that are not resident yet (one buffer set
    // and one submit for all of them) and returns that batch's number (kNone:
    // all were resident). Throws naming a missing weight, or one whose shape
    // differs from its resident copy's.
    static constexpr size_t kNone = size_t(-1);
    size_t ensure(const Graph& g, const WeightStore& weights);
    rt::BufferView view(const std::string& name) const;
    bool has(const std::string& name) const;
    // Device bytes of every resident weight (slots, alignment included).
    uint64_t bytes() const;
    size_t count() const;
    // A graph build that failed after its ensure() gives that batch back (so a failed
    // build holds no memory), unless a later ensure() found one of its weights resident:
    // then another executor reads it, and it stays.
    void forget(size_t batch);

private:
    struct Slot {
        size_t batch = 0;
        rt::ChunkedBuffers::Slot slot;
        Shape shape;
    };
    struct Batch {
        std::unique_ptr<rt::ChunkedBuffers> buffers;  // null once forgotten
        bool shared = false;                          // a later ensure() relies on it
    };
    rt::Context& ctx_;
    uint64_t align_ = 16;
    mutable std::mutex mutex_;
    std::vector<Batch> batches_;  // one per ensure() that added weights
    std::map<std::string, Slot> slots_;
};

}  // namespace vtloc
