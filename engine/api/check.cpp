// vtloc::api::check and check_ops: the engine's checks (engine/check/) behind
// the public API's result structs.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>

#include "engine/api/api_internal.h"
#include "engine/check/device_report.h"
#include "engine/check/fault_injection.h"
#include "engine/check/graph_check.h"
#include "engine/check/op_selftest.h"
#include "engine/io/splitmix64.h"
#include "engine/io/touch_sequence.h"
#include "engine/model/tactile_encoder.h"
#include "engine/tour_cycle.h"
#include "engine/track/codebook.h"
#include "engine/track/tracker.h"

namespace vtloc::api {

namespace {

CheckError to_api(const check::Comparison& c) {
    CheckError e;
    e.max_abs = c.max_abs;
    e.max_rel = c.max_rel;
    e.tolerance_used = c.worst_ratio;
    e.has_indices = c.index;
    e.mismatches = c.mismatches;
    e.first_mismatch = c.detail;
    return e;
}

CheckDevice device_of(rt::Context& ctx) {
    check::DeviceReport d = check::device_report(ctx);
    return {d.name, d.type, d.vulkan, d.driver, d.limits};
}

// "tactile.layer1.0.conv1" -> "tactile.layer1"; "point.sa2.fps" -> "point.sa2"; "ilu" -> "ilu".
std::string stage_of(const std::string& node) {
    const size_t a = node.find('.');
    if (a == std::string::npos) return node;
    const std::string first = node.substr(0, a);
    if (first != "tactile" && first != "point") return first;
    const size_t b = node.find('.', a + 1);
    return b == std::string::npos ? node : node.substr(0, b);
}

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// check_tracker's shapes: the codebook's maps at `want` samples spread over it (0: all) against
// the CPU reference's render of them.
CodebookCheck check_codebook(const track::Codebook& b, const track::Surface& s, int64_t want, const CheckTolerance& tol) {
    CodebookCheck c;
    c.samples = b.n_samples();
    c.checked = want == 0 ? c.samples : std::min(want, c.samples);
    const int64_t GG = b.G * b.G;
    std::vector<int64_t> rows;
    std::vector<float> got;
    for (int64_t k = 0; k < c.checked; ++k) {
        rows.push_back(k * c.samples / c.checked);
        got.insert(got.end(), b.heights.begin() + rows.back() * GG, b.heights.begin() + (rows.back() + 1) * GG);
    }
    const std::vector<float> ref = track::render_codebook_rows(nullptr, s, rows, b.options);
    HostTensor rows_got({c.checked, GG}, got);
    check::testing::apply_fault("codebook.heights", rows_got);  // tests only: a render gone wrong
    const check::Comparison cmp = check::compare(rows_got, HostTensor({c.checked, GG}, ref), {tol.abs, tol.rel});
    c.heights = to_api(cmp);
    c.ok = cmp.ok;
    return c;
}

// check_tracker's touch_terms: a smooth log term over the surface's samples (a bump around a
// random sample, in [-2, 0]: beliefs stay spread, as a real touch term leaves them), jittered
// per spin.
std::vector<float> seeded_term(const track::Surface& s, io::SplitMix64& rng) {
    const int64_t S = s.n_samples(), NS = s.n_spin();
    const size_t c = size_t(rng.uniform() * double(S));
    const double w = 10 + 20 * rng.uniform();  // mm
    std::vector<float> term(size_t(S * NS));
    for (int64_t k = 0; k < S; ++k) {
        double d2 = 0;
        for (size_t a = 0; a < 3; ++a) d2 += std::pow(double(s.samples[9 * size_t(k) + a]) - s.samples[9 * c + a], 2);
        for (int64_t j = 0; j < NS; ++j) term[size_t(k * NS + j)] = float(-2 + 2 * std::exp(-d2 / (2 * w * w)) - 0.1 * rng.uniform());
    }
    return term;
}

// The graph check's nodes and outputs into the API's structs (check and check_tracker).
void fill_graph(const check::GraphCheck& g, std::vector<NodeCheck>& nodes, std::vector<OutputCheck>& outputs) {
    for (const check::NodeCheck& n : g.nodes) {
        NodeCheck o;
        o.node = n.node;
        o.op = n.op;
        o.stage = stage_of(n.node);
        o.input_shapes.assign(n.input_shapes.begin(), n.input_shapes.end());
        o.output_shapes.assign(n.output_shapes.begin(), n.output_shapes.end());
        o.dispatches = n.dispatches;
        o.error = to_api(n.cmp);
        o.error.has_indices = n.has_index;
        o.error.indices_equal = n.indices_equal;
        o.failure = n.error;
        o.ok = n.ok();
        nodes.push_back(std::move(o));
    }
    for (const check::OutputCheck& out : g.outputs) {
        OutputCheck o{out.name, to_api(out.cmp), out.cmp.ok};
        o.error.indices_equal = !out.cmp.index || out.cmp.ok;
        outputs.push_back(std::move(o));
    }
}

}  // namespace

CheckResult check(Context& context, const CheckOptions& options) {
    return guarded([&] {
        const auto t0 = std::chrono::steady_clock::now();
        rt::Context& ctx = ContextAccess::rt(context);
        CheckResult r;
        ModelInfo info;
        ModelFile file = load_checked_model(options.model, info);
        VtlocRunner runner(std::move(file.weights), std::move(file.config), &ctx);
        r.model_name = info.name;
        const TactileImage image = load_tactile_image(options.tactile);
        const HostTensor cloud = cloud_tensor(load_point_cloud(options.object, info.sample_points));
        VtlocRunner::Prepared p =
            runner.prepare_once(tactile_image_input(image.rgb.data(), image.rgb.size(), image.height, image.width), cloud, nullptr);

        const check::GraphCheck g = check::check_graph(ctx, p.graph, runner.weights(), p.inputs);
        r.device = device_of(ctx);
        r.node_tolerance = {check::kNodeTolerance.abs, check::kNodeTolerance.rel};
        r.end_to_end_tolerance = {check::kEndToEndTolerance.abs, check::kEndToEndTolerance.rel};
        fill_graph(g, r.nodes, r.outputs);
        r.first_failure = g.first_failure;
        r.ok = g.ok();
        r.gpu_ms = g.gpu_ms;
        r.cpu_ms = g.cpu_nodes_ms + g.cpu_full_ms;
        r.wall_ms = ms_since(t0);
        return r;
    });
}


TrackerCheckResult check_tracker(Context& context, const TrackerCheckOptions& options) {
    return guarded([&] {
        const auto t0 = std::chrono::steady_clock::now();
        if (options.touches.empty()) throw Error("check_tracker: a touches file is needed (its motions drive the check)");
        const io::TouchSequence seq = io::read_touch_sequence(options.touches);
        const std::string object = options.object.empty() ? seq.object : options.object;
        if (object.empty()) throw Error(options.touches + ": no \"object\" in the file; name one (--object)");
        std::vector<std::optional<track::Rigid>> motions = seq.relative_motions(options.touches);
        if (motions.size() < 2) throw Error(options.touches + ": the tracker check needs at least two touches");
        if (options.there_and_back) {  // back over the tour to its first pose, as vtloc-bench goes on
            std::vector<Rigid> tour;
            for (size_t k = 1; k < motions.size(); ++k) tour.push_back(*motions[k]);
            const int n = int(tour.size());
            for (int i = n + 1; i <= 2 * n; ++i) motions.push_back(tour_motion(tour, "return", i));
        }
        TrackerOptions to;
        to.hypotheses = options.hypotheses;
        to.object_units = options.object_units;
        to.codebook_cache = options.codebook_cache;
        if (options.codebook_samples < 0) throw Error("check_tracker: codebook_samples must be >= 0 (0: all)");
        if (!options.shapes && (options.rendered_frames || !options.calibration.empty() || !options.background.empty() ||
                                !options.codebook_cache.empty() || options.codebook_samples != 0))
            throw Error("check_tracker: rendered_frames, calibration, background, codebook_cache and codebook_samples are for shapes");
        if (options.shapes && options.touch_terms) throw Error("check_tracker: seeded terms or the frames' shapes, not both");
        // The frames (and the empty frame) read before the trackers are made: a missing one is named at once.
        std::optional<TactileImage> background;
        std::vector<TactileImage> images;
        if (options.shapes) {
            if (!options.background.empty()) background = load_tactile_image(options.background);
            for (const io::SequenceTouch& st : seq.touches) images.push_back(load_tactile_image(st.tactile));
        }
        Tracker api_gpu(context, object, to);
        track::Tracker& gpu = TrackerAccess::core(api_gpu);
        track::Tracker cpu = track::Tracker::cpu_reference_of(gpu);
        gpu.capture_steps(true);
        TrackerCheckResult r;
        r.object = object;
        r.hypotheses = gpu.surface().n_hypotheses();
        double gpu_ms = 0, cpu_ms = 0;
        // With shapes: the codebook's maps against the CPU reference's render; then each frame of the
        // file: the reader's graph checked node by node on it, the shape it read against the CPU
        // reference run's, render-and-compare's term of that shape, the device's and the CPU
        // reference scorer's compared; the device's goes to both trackers.
        std::vector<std::vector<float>> frame_terms;
        if (options.shapes) {
            GelShapeOptions go = options.rendered_frames ? GelShapeOptions::rendered_frames() : GelShapeOptions{};
            go.calibration = options.calibration;
            GelShapeReader reader(context, go);
            GelShapeAccess::Checker shape_check(reader, ContextAccess::rt(context));
            std::error_code ec;
            const bool had_cache = !options.codebook_cache.empty() && std::filesystem::exists(options.codebook_cache, ec);
            const TrackerAccess::ShapeScorers scorers = TrackerAccess::shape_scorers(api_gpu);
            const auto b0 = std::chrono::steady_clock::now();
            r.codebook = check_codebook(*scorers.book, gpu.surface(), options.codebook_samples, r.height_tolerance);
            cpu_ms += ms_since(b0);
            // A cache this check wrote from a render that failed would mislead the next tracker.
            if (!r.codebook.ok && !had_cache && !options.codebook_cache.empty()) std::filesystem::remove(options.codebook_cache, ec);
            for (size_t i = 0; i < seq.touches.size(); ++i) {
                const io::SequenceTouch& st = seq.touches[i];
                const TactileImage& image = images[i];
                const TactileImage* bg = background ? &*background : nullptr;
                ShapeTermCheck tc;
                tc.frame = st.tactile;
                const GelShapeAccess::Checked checked = shape_check.check(image, bg, st.tactile, options.background);
                const GelShape& g = checked.read;  // what reader.read() returns for this frame
                const check::GraphCheck& sg = checked.graph;
                fill_graph(sg, tc.shape_nodes, tc.shape_outputs);
                tc.first_failure = sg.first_failure;
                if (tc.first_failure >= 0 && r.first_shape_failure < 0) r.first_shape_failure = int(r.shape_terms.size());
                gpu_ms += sg.gpu_ms, cpu_ms += sg.cpu_nodes_ms + sg.cpu_full_ms;
                // The shape the term scores comes from the reader's own executor (its memory plan, not
                // the check's keep-all one): against the check's CPU reference run of the same graph.
                const GelShape& ref = checked.reference;
                const int64_t px = int64_t(ref.depth_mm.size());
                const check::Comparison dc = check::compare(HostTensor({px}, g.depth_mm), HostTensor({px}, ref.depth_mm),
                                                            {r.end_to_end_tolerance.abs, r.end_to_end_tolerance.rel});
                tc.depth = to_api(dc);
                for (size_t p = 0; p < ref.mask.size(); ++p) tc.mask_pixels_differ += g.mask[p] != ref.mask[p];
                auto a0 = std::chrono::steady_clock::now();
                frame_terms.push_back(TrackerAccess::shape_term(api_gpu, *scorers.gpu, g));
                gpu_ms += ms_since(a0);
                a0 = std::chrono::steady_clock::now();
                const std::vector<float> c = TrackerAccess::shape_term(api_gpu, *scorers.cpu, g);
                cpu_ms += ms_since(a0);
                const int64_t n = int64_t(c.size());
                const check::Comparison cmp = check::compare(HostTensor({n}, frame_terms.back()), HostTensor({n}, c),
                                                             {r.term_tolerance.abs, r.term_tolerance.rel});
                tc.term = to_api(cmp);
                tc.ok = cmp.ok && sg.ok() && dc.ok && tc.mask_pixels_differ == 0;
                r.shape_terms.push_back(std::move(tc));
            }
        }
        io::SplitMix64 rng(20261207);
        for (size_t i = 0; i < motions.size(); ++i) {
            std::vector<float> term;  // a touch on the way back takes the frame of the touch it returns to
            if (options.shapes) term = frame_terms[size_t(returned_touch(int(seq.touches.size()) - 1, int(i)))];
            if (options.touch_terms) term = seeded_term(gpu.surface(), rng);
            auto a0 = std::chrono::steady_clock::now();
            gpu.add_touch(motions[i], term);
            gpu_ms += ms_since(a0);
            a0 = std::chrono::steady_clock::now();
            cpu.add_touch(motions[i], term);
            cpu_ms += ms_since(a0);
            const std::vector<float>&a = gpu.belief(), &b = cpu.belief();
            float peak = 0;
            for (float v : b) peak = std::max(peak, v);
            const int64_t n = int64_t(b.size());
            const check::Comparison c = check::compare(HostTensor({int64_t(a.size())}, a), HostTensor({n}, b),
                                                       {r.belief_tolerance.abs * peak, r.belief_tolerance.rel});
            TouchCheck t;
            t.touch = int(i + 1);
            t.belief = to_api(c);
            t.ok = c.ok;
            const auto ca = gpu.estimate().contact, cb = cpu.estimate().contact;
            t.contact_mm = std::sqrt((ca[0] - cb[0]) * (ca[0] - cb[0]) + (ca[1] - cb[1]) * (ca[1] - cb[1]) + (ca[2] - cb[2]) * (ca[2] - cb[2]));
            r.touches.push_back(std::move(t));
        }
        rt::Context& ctx = ContextAccess::rt(context);
        const track::Tracker::StepCase* step = gpu.last_step_case();
        if (!step) throw Error("check_tracker: the last step was not kept");  // capture was on: a bug
        const check::GraphCheck g = check::check_graph(ctx, step->graph, gpu.step_weights(), step->inputs);
        fill_graph(g, r.nodes, r.outputs);
        r.device = device_of(ctx);
        r.node_tolerance = {check::kNodeTolerance.abs, check::kNodeTolerance.rel};
        r.end_to_end_tolerance = {check::kEndToEndTolerance.abs, check::kEndToEndTolerance.rel};
        r.first_failure = g.first_failure;
        r.ok = g.ok();
        for (const TouchCheck& t : r.touches) r.ok = r.ok && t.ok;
        for (const ShapeTermCheck& t : r.shape_terms) r.ok = r.ok && t.ok;
        r.ok = r.ok && r.codebook.ok;
        r.gpu_ms = gpu_ms + g.gpu_ms;
        r.cpu_ms = cpu_ms + g.cpu_nodes_ms + g.cpu_full_ms;
        r.wall_ms = ms_since(t0);
        return r;
    });
}

OpsCheckResult check_ops(Context& context, const std::string& filter,
                         const std::function<void(size_t, size_t, const OpCheck&)>& progress) {
    return guarded([&] {
        rt::Context& ctx = ContextAccess::rt(context);
        auto to_op = [](const check::OpCaseResult& c, const check::Tolerance& tol) {
            OpCheck o;
            o.op = c.op;
            o.variant = c.variant;
            o.dispatches = c.dispatches;
            o.error = to_api(c.cmp);
            o.error.indices_equal = !c.cmp.index || c.cmp.ok;
            o.tolerance = {tol.abs, tol.rel};
            o.failure = c.error;
            o.ok = c.ok();
            o.ms = c.ms;
            return o;
        };
        std::function<void(size_t, size_t, const check::OpCaseResult&)> step;
        if (progress)
            step = [&](size_t i, size_t n, const check::OpCaseResult& c) { progress(i, n, to_op(c, c.tol)); };
        const check::OpsCheck c = check::check_ops(ctx, filter, step);
        OpsCheckResult r;
        r.device = device_of(ctx);
        for (const check::OpCaseResult& one : c.cases) r.cases.push_back(to_op(one, one.tol));
        r.uncovered_ops = c.uncovered;
        r.ok = c.ok();
        r.wall_ms = c.ms;
        return r;
    });
}

}  // namespace vtloc::api
