// vtloc shape: the gel's shape from one frame (SPEC 9; docs/gel_shape.md).
#include <cmath>
#include <cstdio>

#include "apps/vtloc/report.h"

namespace vtloc::cli {

namespace {

const char* kHelp =
    "usage: vtloc shape --tactile FRAME.png --out DIR [--background EMPTY.png] [--calibration C]\n"
    "                   [--rendered] [--mask-threshold T] [--sweeps N] [--levels L]\n"
    "                   [--coarse-sweeps N] [--threads N] [--json]\n"
    "\n"
    "The gel's shape from a GelSight frame (SPEC section 9): the colour change against the sensor's\n"
    "empty frame, inverted through the calibration into the gel's slopes, a contact mask, and the\n"
    "indentation inside it (on the GPU). Writes DIR/height.png (16-bit grey, micrometres),\n"
    "DIR/shape.ply (the contact's points, mm) and DIR/shape.png (frame | slope | height | contact).\n"
    "\n"
    "  --tactile FRAME.png    the frame: the calibration's size, or larger with the same aspect\n"
    "                         (resampled; real frames are 240x320 or 480x640)\n"
    "  --background EMPTY.png the sensor's frame with nothing pressed (default: the calibration's)\n"
    "  --calibration C        a Taxim-style calibration (default: the shipped GelSight one,\n"
    "                         data/gelsight, CC BY 4.0)\n"
    "  --out DIR              where to write the three files\n"
    "  --rendered             the reader for frames rendered by `vtloc synth` (gentle presses of\n"
    "                         large objects): mask threshold 0.05 and the solve from a coarse\n"
    "                         start (levels 2, 30 coarse sweeps, 10 sweeps); the options below\n"
    "                         change single values of either reader\n"
    "  --mask-threshold T     the contact: 3x3 mean slope above T (default 0.7, fitted on real\n"
    "                         ball presses)\n"
    "  --sweeps N             the height's SOR sweeps on the frame's grid, 1..10000 (default 50)\n"
    "  --levels L             a coarse start: the grid halved up to L times, 0..8 (default 0: from\n"
    "                         zeros; a wide contact needs it)\n"
    "  --coarse-sweeps N      sweeps on each coarse grid, 1..10000 (default 30; only with levels\n"
    "                         above 0)\n"
    "  --threads N            host threads the reader's tables are built on, 0..256 (default 0:\n"
    "                         up to 4; the outputs do not depend on it)\n"
    "  --json                 print the summary as JSON\n";

}  // namespace

int cmd_shape(Session& s, int argc, char** argv) {
    Args a(argc, argv, 2,
           {{"--tactile"}, {"--background"}, {"--calibration"}, {"--out"}, {"--rendered", false}, {"--mask-threshold"},
            {"--sweeps"}, {"--levels"}, {"--coarse-sweeps"}, {"--threads"}, {"--json", false}});
    if (a.help()) {
        std::fputs(kHelp, stdout);
        return 0;
    }
    const std::string tactile = a.required("--tactile"), out = a.required("--out");
    api::GelShapeOptions o = a.flag("--rendered") ? api::GelShapeOptions::rendered_frames() : api::GelShapeOptions{};
    o.calibration = a.get("--calibration").value_or("");
    o.mask_threshold = a.number("--mask-threshold", o.mask_threshold);
    if (!(o.mask_threshold > 0)) throw UsageError("--mask-threshold must be > 0");
    o.iterations = a.integer("--sweeps", o.iterations, 1, 10000);
    o.levels = a.integer("--levels", o.levels, 0, 8);
    o.coarse_iterations = a.integer("--coarse-sweeps", o.coarse_iterations, 1, 10000);
    o.threads = a.integer("--threads", o.threads, 0, 256);
    const api::TactileImage frame = api::load_tactile_image(tactile);
    std::optional<api::TactileImage> empty;
    const std::string background = a.get("--background").value_or("");
    if (!background.empty()) empty = api::load_tactile_image(background);
    api::GelShapeReader reader(s.gpu(), o);
    const api::GelShape g = read_gel_shape(reader, tactile, frame, empty ? &*empty : nullptr, background);
    double deepest = 0, cx = 0, cy = 0, area = 0;
    for (int r = 0; r < g.height; ++r)
        for (int c = 0; c < g.width; ++c) {
            const size_t i = size_t(r) * size_t(g.width) + size_t(c);
            deepest = std::max(deepest, double(g.depth_mm[i]));
            if (g.mask[i]) cx += c, cy += r, area += 1;
        }
    const std::vector<std::string> files = api::write_gel_shape(out, g, frame);
    if (a.flag("--json")) {
        nlohmann::json j{{"tactile", tactile}, {"size", {g.width, g.height}}, {"mm_per_px", g.mm_per_px},
                         {"max_depth_mm", deepest}, {"contact_area_mm2", area * g.mm_per_px * g.mm_per_px},
                         {"contact_centre_px", area > 0 ? nlohmann::json{cx / area, cy / area} : nlohmann::json(nullptr)},
                         {"outputs", files}};
        std::printf("%s\n", j.dump(2).c_str());
        return 0;
    }
    std::printf("frame     %s (%dx%d) at the calibration's %dx%d, %.4f mm per pixel\n", tactile.c_str(), frame.width,
                frame.height, g.width, g.height, g.mm_per_px);
    if (area > 0)
        std::printf("contact   %.1f mm^2 centred at pixel (%.1f, %.1f); deepest %.3f mm\n", area * g.mm_per_px * g.mm_per_px,
                    cx / area, cy / area, deepest);
    else
        std::printf("contact   none found (no slope above the mask's threshold)\n");
    for (const std::string& f : files) std::printf("wrote     %s\n", f.c_str());
    return 0;
}

}  // namespace vtloc::cli
