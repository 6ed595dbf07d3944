// vtloc calibrate: a sensor calibration of the user's own from ball presses
// (SPEC 9; docs/calibrate.md). The fit is engine/sensor/calibrate's.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "apps/vtloc/report.h"
#include "base/error.h"
#include "engine/io/image.h"
#include "engine/sensor/ball_press.h"
#include "engine/sensor/calibrate.h"
#include "engine/sensor/frame_check.h"

namespace vtloc::cli {

namespace {

namespace fs = std::filesystem;
using sensor::BallPress;
using sensor::Calibration;

const char* kHelp =
    "usage: vtloc calibrate (--presses FRAMES --empty EMPTY.png | --from-calibration C) --out CALIB\n"
    "                       [--ball-mm 4] [--mm-per-px 0.1245] [--circles CIRCLES.csv | --annotated]\n"
    "                       [--hold-out N] [--compare C] [--rounds 8] [--write-inputs DIR] [--json]\n"
    "\n"
    "A Taxim-style calibration of your own GelSight from frames of a ball pressed into the gel\n"
    "(SPEC section 9; docs/calibrate.md): per slope bin and colour channel, a quadratic in the\n"
    "pixel position predicting the colour change, written in the shipped format (vtloc shape\n"
    "--calibration reads it), with a report of how well it explains the presses.\n"
    "\n"
    "  --presses FRAMES       the presses: a folder (its image files, by name) or a comma-separated list\n"
    "  --empty EMPTY.png      the sensor's frame with nothing pressed, the presses' size\n"
    "  --from-calibration C   the presses, empty frame and annotated circles kept in a calibration file\n"
    "                         ('shipped': data/gelsight's 49 real presses), to check the method\n"
    "  --ball-mm D            the ball's diameter, mm (default 4)\n"
    "  --mm-per-px X          the frames' pixel size, mm (default 0.1245, the shipped sensor's)\n"
    "  --circles CSV          each press's contact circle 'cx,cy,r' (pixels, column and row), one line\n"
    "                         per press in order; default: detected from the colour change, then\n"
    "                         refined round by round against the table being fitted\n"
    "  --annotated            with --from-calibration: its annotated circles, not detected ones\n"
    "  --hold-out N           leave every N-th press (N-th, 2N-th, ...) out of the fit and report how\n"
    "                         well the table explains it, beside --compare's table\n"
    "  --compare C            the table to compare with (default: the shipped one, if its size matches)\n"
    "  --rounds R             refinement rounds for detected circles (default 8; 0: detection only)\n"
    "  --out CALIB            the calibration file to write (.safetensors)\n"
    "  --write-inputs DIR     also write the presses as a user gives them: DIR/press_NN.png,\n"
    "                         DIR/empty.png and DIR/circles.csv (the circles the table was fitted with)\n"
    "  --json                 print the report as JSON\n";

io::RgbImage as_rgb(const std::vector<uint8_t>& stored, int H, int W) {
    io::RgbImage im(H, W);
    for (size_t p = 0; p + 2 < stored.size(); p += 3) im.pixels[p] = stored[p + 2], im.pixels[p + 1] = stored[p + 1], im.pixels[p + 2] = stored[p];
    return im;
}

// Frames as the calibration stores them (OpenCV's BGR order), from files read as RGB.
std::vector<uint8_t> stored_order(const io::RgbImage& im) {
    std::vector<uint8_t> v(im.pixels.size());
    for (size_t p = 0; p + 2 < v.size(); p += 3) v[p] = im.pixels[p + 2], v[p + 1] = im.pixels[p + 1], v[p + 2] = im.pixels[p];
    return v;
}

// The empty frame may sit in the presses' folder: it is not a press.
std::vector<std::string> press_files(const std::string& spec, const std::string& empty) {
    std::vector<std::string> files;
    std::error_code ec;
    if (fs::is_directory(spec, ec)) {
        for (const auto& e : fs::directory_iterator(spec, ec)) {
            std::string ext = e.path().extension().string();
            std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
            if (fs::equivalent(e.path(), empty, ec)) continue;
            if (e.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp")) files.push_back(e.path().string());
        }
        std::sort(files.begin(), files.end());
        if (files.empty()) throw Error(spec + ": no image files in the folder");
        return files;
    }
    std::stringstream ss(spec);
    for (std::string f; std::getline(ss, f, ',');)
        if (!f.empty()) files.push_back(f);
    if (files.empty()) throw UsageError("--presses: no frames given");
    return files;
}

void read_circles(const std::string& path, std::vector<BallPress>& presses) {
    std::ifstream in(path);
    if (!in) throw Error(path + ": cannot open the circles file");
    size_t n = 0, line_no = 0;
    for (std::string line; std::getline(in, line);) {
        ++line_no;
        if (line.empty() || line[0] == '#' || line.find_first_not_of(" \t\r") == std::string::npos) continue;
        std::replace(line.begin(), line.end(), ',', ' ');
        std::istringstream ls(line);
        double cx, cy, r;
        if (!(ls >> cx >> cy >> r)) {
            if (n == 0 && line_no == 1) continue;  // a header
            throw Error(path + ": line " + std::to_string(line_no) + " is not 'cx,cy,r'");
        }
        if (n >= presses.size()) throw Error(path + ": more circles than the " + std::to_string(presses.size()) + " presses");
        presses[n].cx = cx, presses[n].cy = cy, presses[n].radius_px = r;
        ++n;
    }
    if (n != presses.size())
        throw Error(path + ": " + std::to_string(n) + " circles for " + std::to_string(presses.size()) + " presses");
}

struct Score {
    double inside = 0, outside = 0;
};

// The table's residuals on presses; circles of radius 0 (detected) are found
// and refined against this very table, as the fit did for its own.
Score score(const Calibration& c, std::vector<BallPress> ps, const std::vector<uint8_t>& empty, const sensor::CalibrateOptions& o,
            int rounds, std::vector<double>* per_press) {
    Score s;
    for (size_t i = 0; i < ps.size(); ++i) {
        BallPress& p = ps[i];
        if (p.radius_px == 0) {
            p = sensor::detected_circle(std::move(p), empty, c.height, c.width, "held-out press " + std::to_string(i));
            for (int r = 0; r < rounds; ++r) p = sensor::refine_circle(c, p, o);
        }
        const sensor::PressResidual r = sensor::press_residual(c, p, o);
        s.inside += r.inside / double(ps.size()), s.outside += r.outside / double(ps.size());
        if (per_press) per_press->push_back(r.inside);
    }
    return s;
}

int run_calibrate(int argc, char** argv) {
    Args a(argc, argv, 2,
           {{"--presses"}, {"--empty"}, {"--from-calibration"}, {"--ball-mm"}, {"--mm-per-px"}, {"--circles"}, {"--annotated", false},
            {"--hold-out"}, {"--compare"}, {"--rounds"}, {"--out"}, {"--write-inputs"}, {"--json", false}});
    if (a.help()) {
        std::fputs(kHelp, stdout);
        return 0;
    }
    const std::string out = a.required("--out");
    const auto from = a.get("--from-calibration");
    if (from.has_value() == a.get("--presses").has_value()) throw UsageError("give --presses (with --empty) or --from-calibration");
    if (a.flag("--annotated") && !from) throw UsageError("--annotated goes with --from-calibration");
    if (a.flag("--annotated") && a.get("--circles")) throw UsageError("--annotated and --circles: give one");
    const double ball_mm = a.number("--ball-mm", 4.0);
    if (!(ball_mm > 0 && ball_mm < 1000)) throw UsageError("--ball-mm must be a diameter in mm, > 0");
    const int hold = a.integer("--hold-out", 0, 0, 1000), rounds = a.integer("--rounds", 8, 0, 100);
    if (hold == 1) throw UsageError("--hold-out 1 would hold out every press; use 2 or more (0: none)");

    sensor::CalibrateOptions o;
    o.ball_radius_mm = ball_mm / 2;
    std::vector<BallPress> presses;
    std::vector<uint8_t> empty;
    int H = 0, W = 0;
    std::string source;
    if (from) {
        const std::string path = *from == "shipped" ? sensor::default_calibration_path() : *from;
        const Calibration c = sensor::load_calibration(path);
        if (c.n_press == 0) throw Error(path + ": holds no press frames");
        presses = sensor::calibration_presses(c);
        empty = c.press_f0, H = c.height, W = c.width, o.mm_per_px = c.mm_per_px, source = path;
        if (!a.flag("--annotated"))
            for (BallPress& p : presses) p.radius_px = 0;
    } else {
        const std::string empty_path = a.required("--empty");
        const io::RgbImage e = io::load_tactile_image(empty_path);
        H = e.height, W = e.width, empty = stored_order(e);
        sensor::check_gel_frame(empty, empty_path);
        for (const std::string& f : press_files(*a.get("--presses"), empty_path)) {
            const io::RgbImage im = io::load_tactile_image(f);
            if (im.height != H || im.width != W)
                throw Error(f + ": " + std::to_string(im.width) + "x" + std::to_string(im.height) + ", but the empty frame " + empty_path +
                            " is " + std::to_string(W) + "x" + std::to_string(H));
            BallPress p;
            p.frame = stored_order(im);
            sensor::check_gel_frame(p.frame, f);
            presses.push_back(std::move(p));
        }
        source = *a.get("--presses");
    }
    o.mm_per_px = a.number("--mm-per-px", o.mm_per_px);
    if (!(o.mm_per_px > 0 && o.mm_per_px < 10)) throw UsageError("--mm-per-px must be > 0 (mm)");
    if (auto cf = a.get("--circles")) read_circles(*cf, presses);
    const bool detected = presses[0].radius_px == 0;

    std::vector<BallPress> fit, held;
    for (size_t i = 0; i < presses.size(); ++i) (hold > 0 && (i + 1) % size_t(hold) == 0 ? held : fit).push_back(presses[i]);
    if (fit.empty()) throw Error("calibrate: no presses left to fit");
    const sensor::CalibrateRun run = sensor::calibrate(fit, empty, H, W, o, rounds);
    sensor::save_calibration(out, run.calib);
    if (auto dir = a.get("--write-inputs")) {
        std::error_code ec;
        fs::create_directories(*dir, ec);
        if (ec) throw Error(*dir + ": cannot create the folder (" + ec.message() + ")");
        io::save_png((fs::path(*dir) / "empty.png").string(), as_rgb(empty, H, W));
        std::ofstream csv(fs::path(*dir) / "circles.csv");
        csv << "cx,cy,r\n";
        for (size_t i = 0; i < run.presses.size(); ++i) {
            char name[32];
            std::snprintf(name, sizeof name, "press_%02zu.png", i);
            io::save_png((fs::path(*dir) / name).string(), as_rgb(run.presses[i].frame, H, W));
            csv << run.presses[i].cx << ',' << run.presses[i].cy << ',' << run.presses[i].radius_px << '\n';
        }
        if (!csv) throw Error(*dir + "/circles.csv: cannot write");
    }

    const Score own = score(run.calib, run.presses, empty, o, 0, nullptr);
    std::optional<Score> held_ours, held_theirs;
    std::string compare_path;
    std::vector<double> per_ours, per_theirs;
    if (!held.empty()) {
        held_ours = score(run.calib, held, empty, o, rounds, &per_ours);
        compare_path = a.get("--compare").value_or(sensor::default_calibration_path());
        const Calibration theirs = sensor::load_calibration(compare_path);
        if (theirs.height == H && theirs.width == W)
            held_theirs = score(theirs, held, empty, o, rounds, &per_theirs);
        else if (a.get("--compare"))
            throw Error(compare_path + ": " + std::to_string(theirs.width) + "x" + std::to_string(theirs.height) +
                        ", not the presses' " + std::to_string(W) + "x" + std::to_string(H));
    }
    const char* circles = detected ? "detected, refined" : a.get("--circles") ? "from --circles" : "annotated";
    if (a.flag("--json")) {
        nlohmann::json j{{"source", source}, {"out", out}, {"size", {W, H}}, {"mm_per_px", o.mm_per_px}, {"ball_mm", ball_mm},
                         {"fitted", fit.size()}, {"circles", circles}, {"rounds", run.rounds}, {"last_move_px", run.last_move_px},
                         {"fit_drgb_inside", own.inside}, {"fit_drgb_outside", own.outside}};
        if (held_ours) {
            j["held_out"] = held.size();
            j["held_drgb_inside"] = held_ours->inside, j["held_drgb_outside"] = held_ours->outside;
            j["held_drgb_inside_per_press"] = per_ours;
            if (held_theirs) {
                j["compare"] = compare_path;
                j["compare_drgb_inside"] = held_theirs->inside, j["compare_drgb_outside"] = held_theirs->outside;
                j["compare_drgb_inside_per_press"] = per_theirs;
            }
        }
        std::printf("%s\n", j.dump(2).c_str());
        return 0;
    }
    std::printf("presses   %zu fitted, %dx%d at %.4f mm per pixel, a %.3g mm ball; circles %s", fit.size(), W, H, o.mm_per_px,
                ball_mm, circles);
    if (detected) std::printf(" (%d rounds, last median move %.2f px)", run.rounds, run.last_move_px);
    std::printf("\nfit       mean |dRGB| %.2f inside the contacts, %.2f outside\n", own.inside, own.outside);
    if (held_ours) {
        std::printf("held out  %zu presses: this table %.2f inside (%.2f outside)", held.size(), held_ours->inside, held_ours->outside);
        if (held_theirs)
            std::printf("; %s %.2f (%.2f): %.2fx", compare_path.c_str(), held_theirs->inside, held_theirs->outside,
                        held_ours->inside / held_theirs->inside);
        std::printf("\n");
    }
    std::printf("wrote     %s\n", out.c_str());
    return 0;
}

}  // namespace

int cmd_calibrate(Session&, int argc, char** argv) {
    try {
        return run_calibrate(argc, argv);
    } catch (const vtloc::Error& e) {  // the sensor layer's errors are the user's input's
        throw api::Error(e.what());
    }
}

}  // namespace vtloc::cli
