#include "engine/track/parallel.h"

#include <algorithm>
#include <exception>
#include <thread>
#include <vector>

namespace vtloc::track {

void parallel_for(size_t n, int most, const std::function<void(size_t)>& body) {
    const size_t cap = most > 0 ? size_t(most) : std::min<size_t>(4, std::max(1u, std::thread::hardware_concurrency()));
    const size_t workers = std::min(n, cap);
    std::vector<std::exception_ptr> errors(workers);
    auto work = [&](size_t w) {
        try {
            for (size_t i = w; i < n; i += workers) body(i);
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

}  // namespace vtloc::track
