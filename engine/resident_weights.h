#pragma once
// A model's weights on the device, each named tensor uploaded once and shared
// by every executor (graph shape) of that model on one context: a new shape
// (image size, batch, K, symmetry, profiling) adds only its activation arena
// and staging. Slots are immutable once written, so executors read them with
// no barrier beyond the upload's own wait.
#include <cstdint>
#include <map>
#include <memory>
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
    // and one submit for all of them). Throws naming a missing weight, or one
    // whose shape differs from its resident copy's.
    void ensure(const Graph& g, const WeightStore& weights);
    rt::BufferView view(const std::string& name) const;
    bool has(const std::string& name) const { return slots_.count(name) != 0; }
    // Device bytes of every resident weight (slots, alignment included).
    uint64_t bytes() const;
    size_t count() const { return slots_.size(); }
    // Batches so far; forget_since(mark) frees what ensure() added after
    // batches() returned mark (a graph build that failed later gives its new
    // weights back, so a failed build holds no memory).
    size_t batches() const { return batches_.size(); }
    void forget_since(size_t mark);

private:
    struct Slot {
        size_t batch = 0;
        rt::ChunkedBuffers::Slot slot;
        Shape shape;
    };
    rt::Context& ctx_;
    uint64_t align_ = 16;
    std::vector<std::unique_ptr<rt::ChunkedBuffers>> batches_;  // one per ensure() that added weights
    std::map<std::string, Slot> slots_;
};

}  // namespace vtloc
