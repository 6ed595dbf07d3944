#pragma once
// vtloc-bench's tracker stage: the multi-touch filter (SPEC 6) on a touches
// file's object and motions, geometry only. Times add_touch (the GPU step with
// its uploads and read-backs) and estimate (the CPU refinement and Bayes
// contact) per touch in the steady state (the online window full, the prior
// in use), on the GPU or on the ops' CPU references (ctx null).
#include <nlohmann/json.hpp>
#include <string>

namespace vtloc {
namespace rt {
class Context;
}
namespace bench {

struct TrackerBenchOptions {
    std::string tour;   // a touches file with "object" (default: examples/potato_tour.json)
    int touches = 12;   // the tour continued (cycle) up to this many touches
    // Past the tour's last touch: "return" goes back over its touches in reverse (each motion
    // inverted), then forward again, so every pose is one the tour pressed on the object, as a
    // robot's would be; "repeat" starts its motions over from the last pose, which puts the
    // later touches off the object (the filter's rescue and deep searches then run at every
    // steady touch: their cost, not a tour's; the only cycle before 2026-12-07).
    std::string cycle = "return";
    int reps = 5;       // trackers run from the first touch
    int window = 8;     // the online window (touches scored exactly; its cost is the evidence's)
};

// JSON: object, hypotheses, samples, spins, spacing_mm, window, touches, cycle, reps,
// surface_build_ms, add_touch_ms / estimate_ms / touch_ms (stats over the
// steady-state touches of every rep), first_touch_ms, device_bytes, host_bytes (the most of any rep), nodes_ms (on the GPU: stats per step node
// of one more, profiled tracker's steady touches; {} on the CPU).
nlohmann::json measure_tracker(rt::Context* ctx, const TrackerBenchOptions& o);

}  // namespace bench
}  // namespace vtloc
