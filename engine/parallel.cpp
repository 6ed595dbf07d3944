#include "engine/parallel.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <thread>
#include <vector>

namespace vtloc {

void parallel_for(size_t n, int most, const std::function<void(size_t)>& body) {
    const size_t cap = most > 0 ? size_t(most) : std::min<size_t>(4, std::max(1u, std::thread::hardware_concurrency()));
    const size_t workers = std::min(n, cap);
    std::vector<std::exception_ptr> errors(workers);
    // Each worker takes the next item when it is done with one: the tracker's modes climb
    // for very different times, and a fixed share left one core idle while the other ran
    // two long climbs. The order items run in changes nothing (each writes its own slot).
    std::atomic<size_t> next{0};
    auto work = [&](size_t w) {
        try {
            for (size_t i; (i = next.fetch_add(1)) < n;) body(i);
        } catch (...) {
            errors[w] = std::current_exception();
        }
    };
    std::vector<std::thread> pool;
    for (size_t w = 1; w < workers; ++w) pool.emplace_back(work, w);
    if (workers > 0) work(0);
    for (std::thread& t : pool) t.join();
    for (const std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);
}

}  // namespace vtloc
