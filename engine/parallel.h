#pragma once
// Host threads for CPU loops whose items write their own slots (the filter's climbs and grid,
// the gel's lookup tables).
#include <cstddef>
#include <functional>

namespace vtloc {

// body(i) for i in [0, n) on up to `most` threads, each taking the next i when free (0: up to 4 of the host's;
// fewer for small n); the first exception any of them throws is rethrown here.
void parallel_for(size_t n, int most, const std::function<void(size_t)>& body);

}  // namespace vtloc
