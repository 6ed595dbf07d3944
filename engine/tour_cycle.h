#pragma once
// How a tour of motions goes on past its last touch: vtloc-bench's tracker stage
// (bench/README.md) and `vtloc check --tracker`'s way back (engine/api/check.cpp).
// Header-only, beside engine/rigid.h: tests/test_tour_cycle.cpp checks it.
#include <string>
#include <vector>

#include "base/error.h"
#include "engine/rigid.h"

namespace vtloc {

// The cycles tour_motion knows; vtloc-bench asks before its first stage, minutes before the tracker's.
inline bool known_tour_cycle(const std::string& cycle) { return cycle == "return" || cycle == "repeat"; }

// The motion into touch i (i >= 1; touch 0 has none) of a tour of n >= 1 motions, continued:
// "return" goes back over the tour's touches in reverse (each motion inverted) and then forward
// again, period 2n, so every pose is one the tour pressed on the object; "repeat" starts the
// motions over from the last pose (which leaves the object). Throws on anything else.
inline Rigid tour_motion(const std::vector<Rigid>& tour, const std::string& cycle, int i) {
    if (tour.empty() || i < 1) throw Error("tour_motion: needs a motion and i >= 1");
    const size_t n = tour.size(), k = size_t(i - 1);
    if (!known_tour_cycle(cycle)) throw Error("a tour's cycle is return or repeat, got '" + cycle + "'");
    if (cycle == "repeat") return tour[k % n];
    const size_t j = k % (2 * n);
    return j < n ? tour[j] : inverse(tour[2 * n - 1 - j]);
}

// Under "return", the tour's touch (0..n) whose pose touch i takes: the check gives a touch
// on the way back that touch's frame.
inline int returned_touch(int n, int i) {
    if (n < 1 || i < 0) throw Error("returned_touch: needs a motion and i >= 0");
    const int j = i % (2 * n);
    return j <= n ? j : 2 * n - j;
}

}  // namespace vtloc
