// vtloc eval: the rows that need no trained model (Chance, Point Filtering, Codebook).
#include <algorithm>
#include <cstdio>
#include <numeric>
#include <filesystem>

#include "apps/vtloc/eval.h"
#include "base/error.h"
#include "engine/io/mesh_formats.h"
#include "engine/sensor/calibration.h"
#include "engine/sim/point_filtering.h"

namespace vtloc::cli::eval {

namespace {

sim::Frame8 frame_of(const api::TactileImage& im) { return {im.height, im.width, im.rgb}; }

}  // namespace

MethodResult run_chance(const std::vector<Job>& jobs) {
    MethodResult res;
    res.method = "Chance";
    res.label = "Chance (analytic)";
    res.note = "analytic";
    for (const Job& job : jobs) {
        // The per-candidate heat-maps do not depend on the touch.
        const std::vector<std::vector<float>> heats = sim::chance_heatmaps(job.geom, job.topk);
        std::vector<sim::TouchScore> scores;
        for (const sim::TouchRecord* t : job.touches)
            scores.push_back(sim::score(sim::chance_metrics(job.geom, t->contact, heats, job.topk)));
        res.scores.push_back(std::move(scores));
    }
    return res;
}

MethodResult run_point_filtering(const sim::Dataset& d, const std::vector<Job>& jobs) {
    MethodResult res;
    res.method = "Point Filtering";
    // ObjectFolder's Point Filtering combines touches; this row is its single-touch form
    // (several touches: vtloc eval --sequence).
    res.label = "Point Filtering (single touch)";
    int without_mesh = 0;
    for (const Job& job : jobs) without_mesh += job.rec->has_mesh ? 0 : 1;
    if (without_mesh > 0) {
        // A row over some of the objects would not be comparable with the others.
        res.skipped = true;
        res.note = "skipped: " + std::to_string(without_mesh) + " of " + std::to_string(jobs.size()) +
                   " objects have no mesh.ply";
        return res;
    }
    sim::Calibration calib;
    try {
        calib = sim::load_calibration(sim::default_calibration_path());
    } catch (const vtloc::Error& e) {
        res.skipped = true;
        res.note = std::string("skipped: no sensor calibration (") + e.what() + ")";
        return res;
    }
    // Render at the calibration's resolution over the dataset sensor's field of view.
    const double mm_per_px = d.sensor.mm_per_px * double(d.sensor.width) / double(calib.width);
    sim::PointFilterOptions pfo;
    char note[96];
    std::snprintf(note, sizeof note, "%d spins, press %.1f mm, 1 - NCC", pfo.spins, pfo.press_mm);
    res.note = note;
    size_t total = 0;
    for (const Job& j : jobs) total += j.touches.size() + 1;
    Progress progress("point filtering", total);
    int unrenderable = 0;
    for (const Job& job : jobs) {
        const sim::ObjectRecord& o = *job.rec;
        const std::filesystem::path dir(o.folder);
        std::vector<sim::Point3> normals;
        for (const sim::TouchRecord* t : o.touches_of("test")) normals.push_back(t->normal);
        std::optional<sim::Frame8> background;
        if (o.has_background) background = frame_of(api::load_tactile_image((dir / "background.png").string()));
        std::optional<sim::PointFilter> filter;
        try {
            filter.emplace(calib, io::load_mesh((dir / "mesh.ply").string()), mm_per_px, job.geom.candidates, normals,
                           background, pfo);
        } catch (const vtloc::Error& e) {
            throw api::Error(e.what());
        }
        unrenderable += filter->unrenderable();
        progress.advance();
        std::vector<sim::TouchScore> scores;
        for (const sim::TouchRecord* t : job.touches) {
            const api::TactileImage im = api::load_tactile_image(image_path(o, *t));
            std::vector<int> ranking;
            try {
                ranking = filter->ranking(frame_of(im));
            } catch (const vtloc::Error& e) {
                throw api::Error(image_path(o, *t) + ": " + e.what());
            }
            const sim::Point3 pred = job.geom.candidates[size_t(ranking[0])];
            scores.push_back(sim::score(sim::touch_metrics(job.geom, pred, t->contact, ranking, {}, job.topk)));
            progress.advance();
        }
        res.scores.push_back(std::move(scores));
    }
    progress.finish();
    if (unrenderable > 0) res.note += ", " + std::to_string(unrenderable) + " candidates not renderable (ranked last)";
    return res;
}

MethodResult run_codebook(Session& s, const std::vector<Job>& jobs, api::Backend backend) {
    MethodResult res;
    res.method = "Codebook";
    res.label = "Codebook (MidasTouch-style)";
    int without_mesh = 0;
    for (const Job& job : jobs) without_mesh += job.rec->has_mesh ? 0 : 1;
    if (without_mesh > 0 || backend != api::Backend::Gpu) {
        res.skipped = true;
        res.note = without_mesh > 0 ? "skipped: " + std::to_string(without_mesh) + " of " + std::to_string(jobs.size()) + " objects have no mesh.ply"
                                    : "skipped: render-and-compare runs on the GPU only (--backend cpu)";
        return res;
    }
    // The paper's candidates protocol: poses at the object's candidates only, the belief from
    // the frame's gel shape against what each would press (SPEC 9), candidates ranked by it.
    size_t total = 0, blind = 0, touches = 0;
    for (const Job& j : jobs) total += j.touches.size();
    Progress progress("codebook", total);
    api::GelShapeReader reader(s.gpu(), api::GelShapeOptions::rendered_frames());
    int spins = 0;
    for (const Job& job : jobs) {
        const sim::ObjectRecord& o = *job.rec;
        const std::filesystem::path dir(o.folder);
        api::TrackerOptions to;
        for (const sim::Point3& c : job.geom.candidates) to.candidates.push_back({c[0], c[1], c[2]});
        api::Tracker tracker(s.gpu(), (dir / "mesh.ply").string(), to);
        spins = tracker.n_spin();
        std::optional<api::TactileImage> empty;
        if (o.has_background) empty = api::load_tactile_image((dir / "background.png").string());
        std::vector<sim::TouchScore> scores;
        for (const sim::TouchRecord* t : job.touches) {
            const std::string frame = image_path(o, *t);
            const api::GelShape shape = read_gel_shape(reader, frame, api::load_tactile_image(frame), empty ? &*empty : nullptr,
                                                       o.has_background ? (dir / "background.png").string() : "");
            blind += std::none_of(shape.mask.begin(), shape.mask.end(), [](uint8_t m) { return m != 0; });
            ++touches;
            const api::TrackerEstimate e = tracker.evaluate_window({}, {}, nullptr, {&shape});
            if (e.sample_belief.size() != job.geom.candidates.size())
                throw api::Error("codebook: the belief is over " + std::to_string(e.sample_belief.size()) + " poses, not the " +
                                 std::to_string(job.geom.candidates.size()) + " candidates");
            std::vector<int> ranking(job.geom.candidates.size());
            std::iota(ranking.begin(), ranking.end(), 0);
            std::stable_sort(ranking.begin(), ranking.end(), [&](int a, int b) { return e.sample_belief[size_t(a)] > e.sample_belief[size_t(b)]; });
            const sim::Point3 pred = job.geom.candidates[size_t(ranking[0])];
            scores.push_back(sim::score(sim::touch_metrics(job.geom, pred, t->contact, ranking, {}, job.topk)));
            progress.advance();
        }
        res.scores.push_back(std::move(scores));
    }
    progress.finish();
    char note[160];
    std::snprintf(note, sizeof note, "render-and-compare alone at the candidates' poses, %d spins; %zu of %zu frames show no contact to the gel-shape reader (no evidence)",
                  spins, blind, touches);
    res.note = note;
    return res;
}

}  // namespace vtloc::cli::eval
