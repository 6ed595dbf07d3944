// The dataset builder behind `vtloc synth` (docs/dataset.md).
#include "engine/sim/dataset_builder.h"
#include "engine/sim/object_builder.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <thread>

#include "base/error.h"
#include "engine/io/image.h"
#include "engine/io/mesh_formats.h"
#include "engine/io/splitmix64.h"
#include "engine/sim/partial_view.h"
#include "engine/sim/dataset.h"
#include "engine/sim/shapes.h"
#include "engine/sim/touch_renderer.h"
#include "engine/sim/uniformity.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace vtloc::sim {

namespace {


std::string trim(const std::string& s) {
    size_t a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
    return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

std::string object_name(const std::string& source) {
    if (source.rfind("shape:", 0) == 0) return source.substr(6);
    return fs::path(source).stem().string();
}

std::string options_json(const BuildOptions& o) {
    json j = {{"seed", o.seed},           {"contacts", o.contacts},         {"test_fraction", o.test_fraction},
              {"extra", o.extra},         {"n_points", o.n_points},         {"max_tilt_deg", o.max_tilt_deg},
              {"press_min_mm", o.press_min_mm}, {"press_max_mm", o.press_max_mm},
              {"min_separation_mm", o.min_separation_mm}, {"unseen_fraction", o.unseen_fraction},
              {"randomize_train_look", o.randomize_train_look}, {"calibration", o.calibration},
              {"background", o.background}, {"mm_per_px", o.mm_per_px ? *o.mm_per_px : 0.0}};
    if (o.extra_views != 1) j["extra_views"] = o.extra_views;  // absent: datasets built before it still resume
    if (o.indentation) j["indentation"] = true;
    return j.dump();
}

}  // namespace

std::vector<ObjectSource> read_object_list(const std::string& path, const std::string& mesh_dir) {
    std::ifstream f(path);
    if (!f) throw Error(path + ": cannot read the object list");
    fs::path base = mesh_dir.empty() ? fs::path(path).parent_path() : fs::path(mesh_dir);
    std::vector<ObjectSource> out;
    std::string line;
    int lineno = 0;
    while (std::getline(f, line)) {
        ++lineno;
        line = trim(line.substr(0, line.find('#')));
        if (line.empty()) continue;
        std::istringstream in(line);
        ObjectSource s;
        in >> s.source;
        const std::string where = path + ":" + std::to_string(lineno);
        for (std::string word; in >> word;) {
            if (word.rfind("half-turn:", 0) == 0) {
                const std::string a = word.substr(10);
                if (a != "x" && a != "y" && a != "z") throw Error(where + ": '" + word + "': the axis must be x, y or z");
                if (s.half_turn) throw Error(where + ": the half turn is given twice");
                if (!s.split.empty()) throw Error(where + ": expected '<source> [scale_mm] [half-turn:x|y|z] [seen|unseen]'");
                if (s.source.rfind("shape:", 0) == 0)
                    throw Error(where + ": '" + word + "': a procedural shape declares its own symmetry");
                s.half_turn = a[0];
                continue;
            }
            if (word == "seen" || word == "unseen") {
                if (!s.split.empty()) throw Error(where + ": the split is given twice");
                s.split = word;
                continue;
            }
            if (s.scale_mm || !s.split.empty() || s.half_turn)
                throw Error(where + ": expected '<source> [scale_mm] [half-turn:x|y|z] [seen|unseen]'");
            char* end = nullptr;
            double v = std::strtod(word.c_str(), &end);
            if (*end || !(v > 0) || !std::isfinite(v))
                throw Error(where + ": scale '" + word + "' is not a positive number (nor seen/unseen)");
            s.scale_mm = v;
        }
        if (s.source.rfind("shape:", 0) != 0 && fs::path(s.source).is_relative()) s.source = (base / s.source).string();
        out.push_back(s);
    }
    if (out.empty()) throw Error(path + ": no objects listed");
    return out;
}

namespace {

void check_options(const std::vector<ObjectSource>& objects, const BuildOptions& opt) {
    if (objects.empty()) throw Error("synth: no objects given");
    if (opt.contacts < 2) throw Error("synth: --contacts must be at least 2 (train and test)");
    if (opt.n_points < 1) throw Error("synth: --n-points must be positive");
    if (opt.max_tilt_deg < 0 || opt.max_tilt_deg > 10) throw Error("synth: tilt must be within 0..10 degrees");
    if (!(opt.press_min_mm > 0) || opt.press_max_mm < opt.press_min_mm)
        throw Error("synth: press depth range must be positive and ordered");
}

// The user's empty sensor frame, resized to the calibration's, in stored (BGR)
// order; empty without one.
std::vector<float> user_background(const BuildOptions& opt, const Calibration& calib) {
    std::vector<float> background;
    if (opt.background.empty()) return background;
    const io::RgbImage rgb = io::load_tactile_image(opt.background);  // names the file when it cannot
    cv::Mat bg;
    cv::cvtColor(cv::Mat(rgb.height, rgb.width, CV_8UC3, const_cast<uint8_t*>(rgb.pixels.data())), bg, cv::COLOR_RGB2BGR);
    if (bg.rows != calib.height || bg.cols != calib.width)
        cv::resize(bg, bg, cv::Size(calib.width, calib.height), 0, 0, cv::INTER_AREA);
    background.assign(size_t(calib.height) * size_t(calib.width) * 3, 0);
    for (int y = 0; y < bg.rows; ++y)
        for (int x = 0; x < bg.cols; ++x)
            for (int c = 0; c < 3; ++c)
                background[(size_t(y) * size_t(bg.cols) + size_t(x)) * 3 + size_t(c)] = bg.at<cv::Vec3b>(y, x)[c];
    return background;
}

// build.json records the options: a folder is only ever resumed with the same ones.
void check_stamp(const BuildOptions& opt) {
    fs::create_directories(fs::path(opt.out) / "objects");
    const fs::path stamp = fs::path(opt.out) / "build.json";
    const std::string want = options_json(opt);
    if (fs::exists(stamp)) {
        std::ifstream f(stamp);
        std::string have((std::istreambuf_iterator<char>(f)), {});
        if (trim(have) != want)
            throw Error(opt.out + ": was built with other options (build.json); use another folder or delete it");
    } else {
        write_file_atomic(stamp.string(), want + "\n");
    }
}

std::vector<Job> make_jobs(const std::vector<ObjectSource>& objects) {
    std::vector<Job> jobs;
    std::map<std::string, int> seen_names;
    for (size_t i = 0; i < objects.size(); ++i) {
        Job j{int(i), objects[i], object_name(objects[i].source)};
        if (j.name.empty()) throw Error(objects[i].source + ": cannot name the object");
        if (seen_names[j.name]++) j.name += "_" + std::to_string(seen_names[j.name]);
        jobs.push_back(j);
    }
    return jobs;
}

// Every object built (or read back when already built) on opt.threads threads.
std::vector<ObjectRecord> build_all(const std::vector<Job>& jobs, Shared& sh, int& resumed_count) {
    const BuildOptions& opt = sh.opt;
    std::vector<ObjectRecord> built(jobs.size());
    std::vector<std::string> errors(jobs.size());
    std::atomic<int> next{0}, done{0}, resumed{0};
    auto worker = [&]() {
        for (int i; (i = next++) < int(jobs.size());) {
            fs::path dir = fs::path(opt.out) / "objects" / jobs[size_t(i)].name;
            try {
                if (fs::exists(dir / "object.json")) {
                    built[size_t(i)] = read_built_object(dir);
                    resumed++;
                } else {
                    built[size_t(i)] = build_object(jobs[size_t(i)], sh);
                }
                if (opt.view && !has_partial_view(dir)) {  // written after the folder is in place
                    // Seeded by the dataset seed and the object's name: the same view on any thread count.
                    uint64_t h = opt.seed ^ 0x7669657700000000ull;
                    for (char ch : jobs[size_t(i)].name) h = (h ^ uint8_t(ch)) * 0x100000001B3ull;
                    write_partial_view(dir, render_partial_view(io::load_mesh((dir / "mesh.ply").string()), h,
                                                                opt.n_points));
                }
            } catch (const std::exception& e) {
                errors[size_t(i)] = e.what();
            }
            int d = ++done;
            if (opt.progress) {
                std::lock_guard<std::mutex> lock(sh.mu);
                opt.progress(d, int(jobs.size()), sh.touches.load());
            }
        }
    };
    int nthreads = opt.threads > 0 ? opt.threads : int(std::max(1u, std::thread::hardware_concurrency()));
    nthreads = std::min(nthreads, int(jobs.size()));
    std::vector<std::thread> pool;
    for (int t = 1; t < nthreads; ++t) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
    for (const auto& e : errors)
        if (!e.empty()) throw Error(e);
    resumed_count = resumed;
    return built;
}

// Object-level 7:3 split, stratified by subset, from the dataset seed, over the
// objects whose list line does not pin their split (all of them, in a list
// without pins: the split every earlier dataset was built with).
void split_objects(std::vector<ObjectRecord>& built, const std::vector<ObjectSource>& sources, const BuildOptions& opt) {
    io::SplitMix64 split_rng(opt.seed ^ 0x5EEDull);
    for (const char* subset : {"non-uniform", "uniform"}) {
        std::vector<size_t> idx;
        for (size_t i = 0; i < built.size(); ++i) {
            if (!sources[i].split.empty()) built[i].object_split = sources[i].split;
            else if (built[i].subset == subset) idx.push_back(i);
        }
        for (size_t i = idx.size(); i > 1; --i) std::swap(idx[i - 1], idx[size_t(split_rng.next_u64() % i)]);
        size_t n_unseen = size_t(std::lround(opt.unseen_fraction * double(idx.size())));
        if (idx.size() >= 2) n_unseen = std::clamp<size_t>(n_unseen, 1, idx.size() - 1);
        else n_unseen = 0;
        for (size_t k = 0; k < idx.size(); ++k) built[idx[k]].object_split = k < n_unseen ? "unseen" : "seen";
    }
}

}  // namespace

BuildReport build_dataset(const std::vector<ObjectSource>& objects, const BuildOptions& opt) {
    auto t0 = std::chrono::steady_clock::now();
    check_options(objects, opt);
    Calibration calib = load_calibration(opt.calibration.empty() ? default_calibration_path() : opt.calibration);
    std::vector<float> background = user_background(opt, calib);
    check_stamp(opt);
    const std::vector<Job> jobs = make_jobs(objects);
    Shared sh{opt, calib, background};
    int resumed = 0;
    std::vector<ObjectRecord> built = build_all(jobs, sh, resumed);
    split_objects(built, objects, opt);

    Dataset d;
    d.root = opt.out;
    d.seed = opt.seed;
    d.n_points = opt.n_points;
    d.sensor.height = calib.height;
    d.sensor.width = calib.width;
    d.sensor.mm_per_px = opt.mm_per_px ? *opt.mm_per_px : calib.mm_per_px;
    d.sensor.calibration = opt.calibration.empty() ? "objectfolder_gelsight_calib" : fs::path(opt.calibration).stem().string();
    for (auto& o : built) {
        ObjectRecord e;
        e.name = o.name;
        e.subset = o.subset;
        e.dn_share = o.dn_share;
        e.object_split = o.object_split;
        d.objects.push_back(std::move(e));
    }
    write_dataset_json((fs::path(opt.out) / "dataset.json").string(), d);

    BuildReport r;
    r.objects = int(jobs.size());
    r.resumed = resumed;
    r.touches = sh.touches;
    r.rejected = sh.rejected;
    r.notes = sh.notes;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace vtloc::sim
