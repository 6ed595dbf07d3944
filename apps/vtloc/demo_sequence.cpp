// vtloc demo's default: the multi-touch filter on a shipped tour (SPEC 6), the
// error after each touch, and the belief's convergence as one picture.
#include <chrono>
#include <cmath>
#include <cstdio>

#include "apps/vtloc/report.h"
#include "engine/io/touch_sequence.h"

namespace vtloc::cli {

namespace fs = std::filesystem;

int demo_sequence(Session& s, const fs::path& json_path, const fs::path& model_path, bool geometry_only,
                  const api::LocalizeOptions& opt, const fs::path& out) {
    const io::TouchSequence seq = io::read_touch_sequence(json_path.string());
    if (seq.object.empty()) throw api::Error(json_path.string() + ": a demo sequence names its \"object\"");
    for (size_t i = 0; i < seq.touches.size(); ++i)
        if (!seq.touches[i].contact)
            throw api::Error(json_path.string() + ": touch " + std::to_string(i + 1) + " has no true \"contact\" to compare with");
    std::optional<api::Model> model;
    std::optional<api::Object> object;
    if (!geometry_only) {
        model.emplace(s.gpu(), model_path.string());
        print_model(model->info(), is_shipped_random_model(model_path.string()));
        object = model->encode_object(seq.object);
    }
    std::printf("device    %s\n", s.gpu().device().name.c_str());
    api::Tracker tracker(s.gpu(), seq.object, api::TrackerOptions{});
    std::printf("object    %s: %.0f mm, hypotheses %zu surface samples x %d spins (%.2f mm apart)\n", seq.object.c_str(),
                seq.object_diameter_mm, tracker.sample_points().size() / 3, tracker.n_spin(), tracker.spacing_mm());
    std::printf("sequence  %s: %zu touches, %s\n", json_path.string().c_str(), seq.touches.size(), seq.where.c_str());
    std::printf("scoring   geometry of the robot's motions%s\n\n", model ? " + the network's heat-map of each touch" : " only");
    std::printf("touch  error (mm)  ND (%%)  belief within 5 mm  time (ms)\n");
    const std::vector<std::optional<Rigid>> motions = seq.relative_motions(json_path.string());
    std::vector<api::TrackerEstimate> steps;
    std::vector<std::array<double, 3>> truths;
    std::vector<std::string> captions;
    for (size_t i = 0; i < seq.touches.size(); ++i) {
        const auto t0 = std::chrono::steady_clock::now();
        std::optional<api::TouchResult> r;
        if (model) r = model->localize(*object, api::load_tactile_image(seq.touches[i].tactile), opt);
        std::optional<api::Motion> m;
        if (motions[i]) m = api::Motion{motions[i]->R, motions[i]->t};
        tracker.add_touch(m, r ? &*r : nullptr, object ? &*object : nullptr);
        steps.push_back(tracker.estimate());
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        const std::array<double, 3>& truth = *seq.touches[i].contact;
        const api::TrackerEstimate& e = steps.back();
        const double err = std::hypot(e.contact[0] - truth[0], e.contact[1] - truth[1], e.contact[2] - truth[2]);
        const double nd = seq.object_diameter_mm > 0 ? 100 * err / seq.object_diameter_mm : NAN;
        std::printf("%5zu  %10.1f  %6.1f  %18.2f  %9.0f\n", i + 1, err, nd, e.mass_within_5mm, ms);
        truths.push_back(truth);
        char cap[96];
        std::snprintf(cap, sizeof cap, "after touch %zu: error %.1f mm", i + 1, err);
        captions.push_back(cap);
    }
    make_folder(out.string());
    const std::string png = (out / "belief.png").string();
    api::render_tracker_png(png, tracker, steps, captions, truths);
    std::printf("\nThe first touches leave the place open (many surface patches feel alike); each motion\n"
                "rules out the poses it would carry off the surface, until one place remains.\n"
                "A touch's time is the network, the filter's step and its estimate; the first one's also\n"
                "builds their GPU executors (pipelines, memory, recorded commands: once per process).\n");
    std::printf("wrote     %s (the belief after each touch; crosshair: the estimate, diamond: the truth)\n", png.c_str());
    return 0;
}

}  // namespace vtloc::cli
