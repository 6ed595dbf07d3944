// vtloc synth: a synthetic GelSight dataset (docs/dataset.md) from meshes.
// Uses the simulation library (engine/sim), not the public API: the renderer
// is a tool around the engine, not part of it.
#include <unistd.h>

#include <cstdio>

#include "apps/vtloc/cli.h"
#include "base/error.h"
#include "engine/sim/dataset_builder.h"
#include "engine/sim/reality_check.h"
#include "engine/sim/shapes.h"

namespace vtloc::cli {

namespace {

const char* kHelp =
    "usage: vtloc synth --out DIR (--objects LIST | --shape NAME... | --mesh FILE...) [options]\n"
    "       vtloc synth --check-sensor OUT.png\n"
    "\n"
    "Renders simulated GelSight touches (a real sensor's calibration, Taxim-style gel) on each object\n"
    "and writes a dataset in the layout of docs/dataset.md. Deterministic from --seed; an interrupted\n"
    "build resumes object by object (run the same command again).\n"
    "\n"
    "objects:\n"
    "  --objects LIST      one object per line: <mesh file or shape:NAME> [scale_mm] [half-turn:x|y|z]\n"
    "                      [seen|unseen] (a mesh's half turn about its axes: its symmetry)\n"
    "                      (a last word pins the object's split; the others split 7:3 by the seed)\n"
    "  --mesh-dir DIR      where the list's relative mesh paths are (default: the list's folder)\n"
    "  --shape NAME        a procedural shape (repeatable; see --list-shapes)\n"
    "  --mesh FILE         a mesh: .off .obj .ply .stl .gltf .glb (repeatable)\n"
    "  --scale-mm X        largest side of --mesh objects (default: drawn in 50..250 mm)\n"
    "  --list-shapes       print the procedural shapes and exit\n"
    "touches:\n"
    "  --contacts N        train + test contacts per object (default 40; 7:3 split)\n"
    "  --extra N           extra training touches per object, >= 2 mm from test contacts (default 0)\n"
    "  --extra-views V     render each extra contact V times, each with its own spin, press, tilt\n"
    "                      and look (default 1: N contacts; V: N / V contacts)\n"
    "  --n-points N        points per object cloud (default 1024)\n"
    "  --max-tilt DEG      sensor axis tilt, uniform in 0..DEG, at most 10 (default 5)\n"
    "  --plain-look        no appearance randomisation of training touches\n"
    "  --view              also write each object's single-view cloud (view.xyz, view.json:\n"
    "                      what a depth camera far away sees from one seeded direction, no\n"
    "                      normals); adds them to an already built dataset too\n"
    "  --indentation       also write each touch's gel indentation, the renderer's ground-truth\n"
    "                      geometry, as touches/<id>.depth.png (16-bit grey, micrometres)\n"
    "  --seed S            (default 1)\n"
    "  --threads N         (default: all cores)\n"
    "sensor:\n"
    "  --calibration FILE  a Taxim-style calibration (default: the shipped GelSight one)\n"
    "  --background PNG    your sensor's empty frame, replacing the calibration's background\n"
    "  --mm-per-px X       your sensor's pixel size (default: the calibration's, 0.1245)\n"
    "  --check-sensor PNG  render the 49 real ball presses of the calibration, compare, write\n"
    "                      real | rendered | difference to PNG and print the numbers\n";

bool is_terminal() { return isatty(fileno(stderr)) != 0; }

int check_sensor(const std::string& out) {
    sim::Calibration calib = sim::load_calibration(sim::default_calibration_path());
    sim::RealityOptions opt;
    opt.png_path = out;
    sim::RealityReport r = sim::reality_check(calib, opt);
    std::printf("%d real ball presses vs rendered (one contact detector on both):\n", int(r.frames.size()));
    std::printf("  radius error   median %.1f %%, max %.1f %%\n", 100 * r.median_radius_err, 100 * r.max_radius_err);
    std::printf("  centre offset  median %.2f px, max %.2f px\n", r.median_centre_dist, r.max_centre_dist);
    std::printf("  floor          median %.2f px, max %.2f px, %d frames over 3 px: left after the best fit of the\n"
                "                 offsets by a quadratic in the press position (scatter the annotations do not carry)\n",
                r.floor_median_centre_dist, r.floor_max_centre_dist, r.floor_frames_over_3px);
    std::printf("  mean |dRGB|    inside the contact %.2f (max %.2f), outside %.2f (max %.2f)\n",
                r.mean_drgb_inside, r.max_drgb_inside, r.mean_drgb_outside, r.max_drgb_outside);
    std::printf("wrote %s (rows: real | rendered | difference)\n", out.c_str());
    return 0;
}

}  // namespace

int cmd_synth(Session&, int argc, char** argv) {
    Args a(argc, argv, 2,
           {{"--out"}, {"--objects"}, {"--mesh-dir"}, {"--shape", true, true}, {"--mesh", true, true},
            {"--scale-mm"}, {"--list-shapes", false}, {"--contacts"}, {"--extra"}, {"--extra-views"}, {"--n-points"},
            {"--max-tilt"}, {"--plain-look", false}, {"--view", false}, {"--indentation", false}, {"--seed"}, {"--threads"}, {"--calibration"},
            {"--background"}, {"--mm-per-px"}, {"--check-sensor"}});
    if (a.help()) {
        std::fputs(kHelp, stdout);
        return 0;
    }
    try {
        if (a.flag("--list-shapes")) {
            for (const std::string& s : sim::shape_names())
                std::printf("%-16s %.0f mm\n", s.c_str(), sim::shape_scale_mm(s));
            return 0;
        }
        if (auto p = a.get("--check-sensor")) return check_sensor(*p);

        std::vector<sim::ObjectSource> objects;
        if (auto list = a.get("--objects")) objects = sim::read_object_list(*list, a.get("--mesh-dir").value_or(""));
        std::optional<double> scale;
        if (a.get("--scale-mm")) {
            scale = a.number("--scale-mm", 0);
            if (!(*scale > 0)) throw UsageError("--scale-mm must be positive");
        }
        for (const std::string& s : a.all("--shape")) objects.push_back({"shape:" + s, {}});
        for (const std::string& m : a.all("--mesh")) objects.push_back({m, scale});
        if (objects.empty()) throw UsageError("no objects: give --objects, --shape or --mesh");

        sim::BuildOptions o;
        o.out = a.required("--out");
        o.contacts = a.integer("--contacts", 40, 2, 100000);
        o.extra = a.integer("--extra", 0, 0, 1000000);
        o.extra_views = a.integer("--extra-views", 1, 1, 1000);
        o.n_points = a.integer("--n-points", 1024, 1, 1 << 20);
        o.max_tilt_deg = a.number("--max-tilt", 5);
        if (o.max_tilt_deg < 0 || o.max_tilt_deg > 10) throw UsageError("--max-tilt must be within 0..10 degrees");
        o.randomize_train_look = !a.flag("--plain-look");
        o.view = a.flag("--view");
        o.indentation = a.flag("--indentation");
        o.seed = uint64_t(a.integer("--seed", 1, 0, 2147483647));
        o.threads = a.integer("--threads", 0, 0, 256);
        o.calibration = a.get("--calibration").value_or("");
        o.background = a.get("--background").value_or("");
        if (a.get("--mm-per-px")) {
            o.mm_per_px = a.number("--mm-per-px", 0);
            if (!(*o.mm_per_px > 0)) throw UsageError("--mm-per-px must be positive");
        }
        const bool tty = is_terminal();
        if (tty)
            o.progress = [](int done, int total, long touches) {
                std::fprintf(stderr, "\rsynth: %d/%d objects, %ld touches", done, total, touches);
                if (done == total) std::fputc('\n', stderr);
            };
        sim::BuildReport r = sim::build_dataset(objects, o);
        std::printf("wrote %s: %d objects (%d resumed), %ld touches rendered in %.1f s (%.1f touches/s), "
                    "%ld contact draws rejected\n",
                    o.out.c_str(), r.objects, r.resumed, r.touches, r.seconds,
                    r.seconds > 0 ? double(r.touches) / r.seconds : 0.0, r.rejected);
        for (const std::string& n : r.notes) std::printf("note: %s\n", n.c_str());
    } catch (const vtloc::Error& e) {
        throw api::Error(e.what());
    }
    return 0;
}

}  // namespace vtloc::cli
