#include "bench/tracker_bench.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <map>

#include "base/error.h"
#include "bench/clock.h"
#include "bench/model_bench.h"
#include "engine/tour_cycle.h"
#include "engine/io/mesh_formats.h"
#include "engine/io/object.h"
#include "engine/io/touch_sequence.h"
#include "engine/track/tracker.h"

namespace vtloc::bench {

nlohmann::json measure_tracker(rt::Context* ctx, const TrackerBenchOptions& o) {
    const io::TouchSequence seq = io::read_touch_sequence(o.tour);
    if (seq.object.empty()) throw Error(o.tour + ": the tracker bench needs the file's \"object\"");
    std::vector<Rigid> tour;  // the tour's motions, continued by o.cycle for a steady state past the window
    for (const auto& m : seq.relative_motions(o.tour))
        if (m) tour.push_back(*m);
    if (tour.empty()) throw Error(o.tour + ": the tracker bench needs at least two touches");
    tour_motion(tour, o.cycle, 1);  // an unknown cycle fails before any work
    // The surface as api::Tracker builds it from a mesh.
    const auto t0 = std::chrono::steady_clock::now();
    io::TriangleMesh mesh = io::load_mesh(seq.object);
    io::orient_outward(mesh);
    const HostTensor dense = io::tracker_dense_sample(mesh, seq.object);
    const track::Surface surface = track::build_surface(dense, true, track::SurfaceOptions{}, seq.object);
    const double build_ms = ms_since(t0);

    track::FilterOptions fo;
    fo.online_window = o.window;
    // A fresh tracker through the whole tour; after_touch(tracker, i, add_touch's ms) follows each touch.
    const auto walk = [&](track::Tracker& tr, bool profiled, const std::function<void(track::Tracker&, int, double)>& after_touch) {
        tr.profile_steps(profiled);
        for (int i = 0; i < o.touches; ++i) {
            std::optional<Rigid> m;
            if (i) m = tour_motion(tour, o.cycle, i);
            const auto a0 = std::chrono::steady_clock::now();
            tr.add_touch(m);
            after_touch(tr, i, ms_since(a0));
        }
    };
    std::vector<double> add, est, both, first;
    uint64_t bytes = 0, host = 0;
    int window = 0;
    for (int r = 0; r < o.reps; ++r) {
        track::Tracker tr(ctx, surface, fo);
        window = tr.options().online_window;
        walk(tr, false, [&](track::Tracker& t, int i, double a_ms) {
            const auto e0 = std::chrono::steady_clock::now();
            const track::Estimate e = t.estimate();
            const double e_ms = ms_since(e0);
            if (i == 0 && r > 0) first.push_back(a_ms + e_ms);  // rep 0 compiles the pipelines
            if (i >= window) add.push_back(a_ms), est.push_back(e_ms), both.push_back(a_ms + e_ms);
        });
        bytes = tr.device_bytes();
        host = std::max(host, tr.host_bytes());  // the tree and the pair index only where a rep made them
    }
    // On the GPU one more tracker, profiled (serial, GPU timestamps): each node's median over
    // the steady touches, steadier than the wall clock on a shared host.
    nlohmann::json nodes = nlohmann::json::object();
    if (ctx) {
        track::Tracker tr(ctx, surface, fo);
        std::map<std::string, std::vector<double>> per;
        walk(tr, true, [&](track::Tracker& t, int i, double) {
            if (i >= t.options().online_window)
                for (const auto& [name, ms] : t.step_node_times()) per[name].push_back(ms);
        });
        for (auto& [name, v] : per) nodes[name] = stats_json(v);
    }
    return {{"object", seq.object}, {"hypotheses", surface.n_hypotheses()}, {"samples", surface.n_samples()},
            {"spins", surface.n_spin()}, {"spacing_mm", surface.spacing_mm}, {"window", window},
            {"touches", o.touches}, {"cycle", o.cycle}, {"reps", o.reps}, {"surface_build_ms", build_ms},
            {"add_touch_ms", stats_json(add)}, {"estimate_ms", stats_json(est)}, {"touch_ms", stats_json(both)},
            {"first_touch_ms", first.empty() ? nlohmann::json(nullptr) : stats_json(first)}, {"device_bytes", bytes}, {"host_bytes", host},
            {"nodes_ms", nodes}};
}

}  // namespace vtloc::bench
