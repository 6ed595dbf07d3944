#include "bench/gel_bench.h"

#include <chrono>
#include <map>
#include <string>
#include <vector>

#include "bench/clock.h"
#include "bench/model_bench.h"
#include "engine/io/mesh_formats.h"
#include "engine/io/object.h"
#include "engine/sensor/gel_shape.h"
#include "engine/sensor/gel_shape_gpu.h"
#include "engine/sim/primitives.h"
#include "engine/sim/touch_renderer.h"
#include "engine/track/codebook.h"
#include "engine/track/surface.h"

namespace vtloc::bench {

namespace {

// One frame read with both solves, 50 sweeps from zeros (the real frames' default) and the coarse
// start (the rendered frames'), under the mask threshold its reader uses; `uses` names its
// reader's solve. Per solve: the GPU's ms a frame (wall clock) and the solve's own GPU time (its
// nodes' timestamps, a profiled twin: steadier than the wall clock on a shared host).
nlohmann::json compare_solves(rt::Context& ctx, const sensor::Calibration& c, const sensor::GradientLut& lut,
                              const std::vector<uint8_t>& frame, const std::vector<uint8_t>& empty, const sensor::ShapeOptions& reader,
                              int reps) {
    sensor::ShapeOptions zeros = reader, coarse = sensor::rendered_frame_options();
    zeros.sor_levels = 0, zeros.sor_iterations = 50;
    coarse.mask_threshold = reader.mask_threshold;
    nlohmann::json j{{"uses", reader.sor_levels > 0 ? "coarse_start" : "from_zeros"}};
    for (const auto& [name, o] : {std::pair<const char*, sensor::ShapeOptions>{"from_zeros", zeros}, {"coarse_start", coarse}}) {
        sensor::GelShapeGpu gpu(ctx, c, lut, o);
        sensor::GelShape shape = gpu.run(frame, empty);
        std::vector<double> ms;
        for (int r = 0; r < reps; ++r) {
            const auto t0 = std::chrono::steady_clock::now();
            shape = gpu.run(frame, empty);
            ms.push_back(ms_since(t0));
        }
        size_t in = 0;
        for (uint8_t m : shape.mask) in += m;
        sensor::GelShapeGpu prof(ctx, c, lut, o, true);
        std::vector<double> solve;
        for (int r = 0; r < reps; ++r) {
            prof.run(frame, empty);
            double sum = 0;
            for (const auto& [label, node_ms] : prof.node_times())
                if (label.rfind("gel.height", 0) == 0) sum += node_ms;
            solve.push_back(sum);
        }
        j[name] = {{"shape_ms", stats_json(ms)}, {"solve_gpu_ms", stats_json(solve)}, {"mask_pixels", in}, {"levels", o.sor_levels},
                   {"sweeps", o.sor_iterations}, {"coarse_sweeps", o.sor_coarse_iterations}};
    }
    return j;
}

// A frame `vtloc synth`'s renderer draws (a 24 mm ball pressed 1 mm), read as vtloc eval reads
// such frames: under their mask threshold nearly the whole frame is contact.
nlohmann::json measure_rendered(rt::Context& ctx, const sensor::Calibration& c, const sensor::GradientLut& lut, int reps) {
    sim::TouchRenderer renderer(c, sim::make_icosphere(24, 5));
    sim::TouchParams tp;
    tp.press_mm = 1.0;
    const sim::Appearance look;
    const sim::Touch t = renderer.render({0, 0, 24}, {0, 0, 1}, tp, look, 7);
    nlohmann::json j = compare_solves(ctx, c, lut, t.image, renderer.background_frame(look), sensor::rendered_frame_options(), reps);
    j["frame"] = "a 24 mm ball pressed 1 mm, rendered";
    return j;
}

}  // namespace

nlohmann::json measure_gel(rt::Context* ctx, const GelBenchOptions& o) {
    const sensor::Calibration c = sensor::load_calibration(sensor::default_calibration_path());
    const size_t bytes = size_t(c.height) * size_t(c.width) * 3;
    const int press = 6;  // a real 4 mm ball press of the shipped calibration
    const std::vector<uint8_t> frame(c.press_imgs.begin() + ptrdiff_t(press * bytes), c.press_imgs.begin() + ptrdiff_t((press + 1) * bytes));
    sensor::GradientLut lut = sensor::build_gradient_lut(c);
    nlohmann::json j{{"frame", "press " + std::to_string(press) + " of the shipped calibration"}, {"size", {c.width, c.height}}};
    std::vector<double> cpu;
    sensor::GelShape shape;
    for (int r = 0; r < o.reps; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        shape = sensor::gel_shape(c, lut, frame, c.press_f0);
        cpu.push_back(ms_since(t0));
    }
    j["shape_cpu_ms"] = stats_json(cpu);
    if (!ctx) return j;
    {  // where the GPU's time goes: node timestamps of a profiled twin, medians over the reps
        sensor::GelShapeGpu prof(*ctx, c, lut, {}, true);
        prof.run(frame, c.press_f0);
        std::map<std::string, std::vector<double>> nodes;
        for (int r = 0; r < o.reps; ++r) {
            prof.run(frame, c.press_f0);
            for (const auto& [label, ms] : prof.node_times()) nodes[label].push_back(ms);
        }
        for (auto& [label, v] : nodes) j["shape_nodes_ms"][label] = stats_json(v);
    }
    sensor::GelShapeGpu gpu(*ctx, c, lut);
    gpu.run(frame, c.press_f0);  // pipelines compiled, arena made
    std::vector<double> ms;
    for (int r = 0; r < o.reps; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        shape = gpu.run(frame, c.press_f0);
        ms.push_back(ms_since(t0));
    }
    j["shape_ms"] = stats_json(ms);
    j["solves"] = compare_solves(*ctx, c, lut, frame, c.press_f0, {}, o.reps);
    j["rendered"] = measure_rendered(*ctx, c, lut, o.reps);
    // Render-and-compare on the object as api::Tracker builds it from a mesh.
    io::TriangleMesh mesh = io::load_mesh(o.object);
    io::orient_outward(mesh);
    const track::Surface surface = track::build_surface(io::tracker_dense_sample(mesh, o.object), true, track::SurfaceOptions{}, o.object);
    const auto t0 = std::chrono::steady_clock::now();
    const track::Codebook book = track::render_codebook(ctx, surface);
    const double render_ms = ms_since(t0);
    track::CodebookScorer scorer(ctx, book, surface, track::ScoreOptions{});
    scorer.term(shape.depth_mm, shape.height, shape.width, c.mm_per_px);  // warm
    std::vector<double> score;
    for (int r = 0; r < o.reps; ++r) {
        const auto s0 = std::chrono::steady_clock::now();
        scorer.term(shape.depth_mm, shape.height, shape.width, c.mm_per_px);
        score.push_back(ms_since(s0));
    }
    j["codebook"] = {{"object", o.object}, {"hypotheses", surface.n_hypotheses()}, {"dense_points", surface.n_dense()},
                     {"render_ms", render_ms}, {"score_ms", stats_json(score)}};
    return j;
}

}  // namespace vtloc::bench
