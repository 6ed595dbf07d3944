#pragma once
// A search structure over the filter's dense points [D, 6], made on first use: the
// tracker's searches that need one (the registration's k-d tree, the pair search's index)
// run only where a window fits poorly, so a tracker should not pay for them at
// construction. get() is safe to call from several threads at once; every caller gets the
// one structure, made once.
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

namespace vtloc::track {

template <class Index>  // constructible from the dense points; bytes() its host memory
class LazyIndex {
public:
    explicit LazyIndex(std::shared_ptr<const std::vector<float>> dense) : dense_(std::move(dense)) {}
    const Index& get() const {
        std::call_once(once_, [this] {
            index_ = Index(*dense_);
            built_ = true;
        });
        return index_;
    }
    bool built() const { return built_; }
    uint64_t bytes() const { return built_ ? index_.bytes() : 0; }  // 0 until made
    bool no_points() const { return dense_->size() < 6; }           // known without making it

private:
    std::shared_ptr<const std::vector<float>> dense_;
    mutable std::once_flag once_;
    mutable Index index_;
    mutable std::atomic<bool> built_{false};
};

}  // namespace vtloc::track
