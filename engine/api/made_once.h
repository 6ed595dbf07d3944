#pragma once
// One object made at its first use by whichever of the trackers sharing the holder asks
// first (with_options' trackers share the codebook scorer and the binned points this way),
// the others then reading the same one. Safe from several threads; a make that throws
// leaves nothing made, so the next use tries again.
#include <memory>
#include <mutex>

namespace vtloc::api {

template <class T>
class MadeOnce {
public:
    template <class Make>
    std::shared_ptr<T> get(Make&& make) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!made_) made_ = make();
        return made_;
    }
    std::shared_ptr<T> peek() const {  // null until made
        std::lock_guard<std::mutex> lock(mutex_);
        return made_;
    }

private:
    mutable std::mutex mutex_;
    std::shared_ptr<T> made_;
};

}  // namespace vtloc::api
