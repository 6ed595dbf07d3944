// The dataset builder behind `vtloc synth` (docs/dataset.md).
#include "engine/sim/dataset_builder.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <thread>

#include "base/error.h"
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

constexpr double kPi = 3.14159265358979323846;

std::string trim(const std::string& s) {
    size_t a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
    return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

std::string object_name(const std::string& source) {
    if (source.rfind("shape:", 0) == 0) return source.substr(6);
    return fs::path(source).stem().string();
}

// Mesh scaled so its largest bounding-box side is scale_mm, centred on its box.
io::TriangleMesh scaled(io::TriangleMesh m, double scale_mm) {
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (size_t i = 0; i < m.vertex_count(); ++i)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], double(m.positions[i * 3 + size_t(k)]));
            hi[k] = std::max(hi[k], double(m.positions[i * 3 + size_t(k)]));
        }
    double side = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    double f = scale_mm / side;
    for (size_t i = 0; i < m.vertex_count(); ++i)
        for (int k = 0; k < 3; ++k) {
            float& v = m.positions[i * 3 + size_t(k)];
            v = float((v - 0.5 * (lo[k] + hi[k])) * f);
        }
    return m;
}

double diameter(const HostTensor& p) {
    double best = 0;
    for (int64_t i = 0; i < p.shape[0]; ++i)
        for (int64_t j = i + 1; j < p.shape[0]; ++j) {
            double s = 0;
            for (int k = 0; k < 3; ++k) {
                double d = double(p.data[size_t(i) * 6 + size_t(k)]) - p.data[size_t(j) * 6 + size_t(k)];
                s += d * d;
            }
            best = std::max(best, s);
        }
    return std::sqrt(best);
}

double dist(const Vec3& a, const Vec3& b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

double uniform(io::SplitMix64& rng, double lo, double hi) { return lo + (hi - lo) * rng.uniform(); }

Appearance random_look(io::SplitMix64& rng) {
    Appearance a;
    a.brightness = uniform(rng, -20, 20);
    for (auto& g : a.gain) g = uniform(rng, 0.85, 1.15);
    a.blur_sigma_px = uniform(rng, 0, 1.0);
    a.noise_sigma = uniform(rng, 1.0, 4.0);
    return a;
}

// Relative motion: pose b in pose a's frame (R_a^T R_b, R_a^T (t_b - t_a)).
void relative(const SensorPose& a, const SensorPose& b, TouchRecord& t) {
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            double s = 0;
            for (int k = 0; k < 3; ++k) s += a.R[size_t(k * 3 + i)] * b.R[size_t(k * 3 + j)];
            t.rel_R[size_t(i * 3 + j)] = s;
        }
        double s = 0;
        for (int k = 0; k < 3; ++k) s += a.R[size_t(k * 3 + i)] * (b.t[size_t(k)] - a.t[size_t(k)]);
        t.rel_t[size_t(i)] = s;
        t.motion[size_t(i)] = b.t[size_t(i)] - a.t[size_t(i)];
    }
}

std::string options_json(const BuildOptions& o) {
    json j = {{"seed", o.seed},           {"contacts", o.contacts},         {"test_fraction", o.test_fraction},
              {"extra", o.extra},         {"n_points", o.n_points},         {"max_tilt_deg", o.max_tilt_deg},
              {"press_min_mm", o.press_min_mm}, {"press_max_mm", o.press_max_mm},
              {"min_separation_mm", o.min_separation_mm}, {"unseen_fraction", o.unseen_fraction},
              {"randomize_train_look", o.randomize_train_look}, {"calibration", o.calibration},
              {"background", o.background}, {"mm_per_px", o.mm_per_px ? *o.mm_per_px : 0.0}};
    return j.dump();
}

struct Job {
    int index = 0;
    ObjectSource src;
    std::string name;
};

struct Shared {
    const BuildOptions& opt;
    const Calibration& calib;
    std::vector<float> background;  // user's empty frame, stored order; empty = calibration's
    std::atomic<long> touches{0}, rejected{0};
    std::mutex mu;
    std::vector<std::string> notes;
};

TouchRecord record(const Touch& t, int id, const std::string& split, const TouchParams& p) {
    TouchRecord r;
    r.id = id;
    r.split = split;
    char name[32];
    std::snprintf(name, sizeof name, "touches/%04d.png", id);
    r.image = name;
    r.contact = t.contact;
    r.normal = t.normal;
    r.R = t.pose.R;
    r.t = t.pose.t;
    r.press_mm = p.press_mm;
    r.spin_deg = p.spin_deg;
    r.tilt_deg = p.tilt_deg;
    return r;
}

void write_png(const fs::path& p, const std::vector<uint8_t>& img, int h, int w) {
    cv::Mat m(h, w, CV_8UC3, const_cast<uint8_t*>(img.data()));
    if (!cv::imwrite(p.string(), m)) throw Error(p.string() + ": cannot write the PNG");
}

// Builds one object into objects/<name>.tmp, then renames it into place.
ObjectRecord build_object(const Job& job, Shared& sh) {
    const BuildOptions& opt = sh.opt;
    io::SplitMix64 rng(opt.seed * 0x9E3779B97F4A7C15ull + uint64_t(job.index) * 0xD1B54A32D192ED03ull + 1);
    io::TriangleMesh mesh;
    double scale;
    if (job.src.source.rfind("shape:", 0) == 0) {
        mesh = make_shape(job.name);
        scale = job.src.scale_mm ? *job.src.scale_mm : shape_scale_mm(job.name);
    } else {
        mesh = io::load_mesh(job.src.source);
        scale = job.src.scale_mm ? *job.src.scale_mm : uniform(rng, 50, 250);
    }
    if (!(scale >= 1 && scale <= 10000))
        throw Error(job.src.source + ": scale " + std::to_string(scale) + " mm is outside 1..10000");
    mesh = scaled(std::move(mesh), scale);

    ObjectRecord o;
    o.name = job.name;
    o.source = job.src.source.rfind("shape:", 0) == 0 ? job.src.source : fs::path(job.src.source).filename().string();
    o.scale_mm = scale;
    o.n_points = opt.n_points;
    o.sample_seed = rng.next_u64() >> 11;
    o.points = io::sample_surface(mesh, opt.n_points, o.sample_seed, job.src.source);
    Uniformity u = measure_uniformity(o.points);
    o.dn_share = u.share_below;
    o.subset = u.uniform ? "uniform" : "non-uniform";
    o.diameter_mm = diameter(o.points);

    TouchRenderer renderer(sh.calib, mesh, opt.mm_per_px);
    Appearance plain;
    if (!sh.background.empty()) plain.background = sh.background;

    // Contact draws: area-weighted surface samples, in batches, each rendered
    // with its own spin/tilt/press; unreachable or too-close ones are skipped.
    struct Accepted {
        Touch touch;
        TouchParams params;
        Vec3 point, normal;  // the draw (the contact is its projection)
    };
    std::vector<Accepted> acc;
    const int want = opt.contacts;
    const int max_draws = 50 * std::max(want, 1) + 200;
    int draws = 0;
    uint64_t draw_seed = rng.next_u64();
    HostTensor pool;
    int64_t pool_at = 0;
    auto next_point = [&](Vec3& p, Vec3& n) {
        if (pool_at >= (pool.shape.empty() ? 0 : pool.shape[0])) {
            pool = io::sample_surface(mesh, 256, draw_seed++, job.src.source);
            pool_at = 0;
        }
        const float* q = &pool.data[size_t(pool_at++) * 6];
        p = {q[0], q[1], q[2]};
        n = {q[3], q[4], q[5]};
    };
    auto draw_params = [&]() {
        TouchParams tp;
        tp.press_mm = uniform(rng, opt.press_min_mm, opt.press_max_mm);
        tp.spin_deg = uniform(rng, 0, 360);
        tp.tilt_deg = uniform(rng, 0, opt.max_tilt_deg);
        tp.tilt_dir_deg = uniform(rng, 0, 360);
        return tp;
    };
    while (int(acc.size()) < want && draws < max_draws) {
        ++draws;
        Vec3 p, n;
        next_point(p, n);
        TouchParams tp = draw_params();
        Touch t = renderer.render(p, n, tp, plain, rng.next_u64());
        if (!t.ok) {
            sh.rejected++;
            continue;
        }
        bool close = false;
        for (const auto& a : acc) close = close || dist(a.touch.contact, t.contact) < opt.min_separation_mm;
        if (close) continue;
        acc.push_back({std::move(t), tp, p, n});
    }
    if (acc.size() < 2)
        throw Error(job.src.source + ": no reachable contacts found (" + std::to_string(draws) + " draws)");
    if (int(acc.size()) < want) {
        std::lock_guard<std::mutex> lock(sh.mu);
        sh.notes.push_back(job.name + ": " + std::to_string(acc.size()) + " of " + std::to_string(want) +
                           " contacts (the rest unreachable or too close)");
    }

    // 7:3 split (a seeded shuffle), test contacts first in id order.
    std::vector<size_t> perm(acc.size());
    std::iota(perm.begin(), perm.end(), 0);
    for (size_t i = perm.size(); i > 1; --i) std::swap(perm[i - 1], perm[size_t(rng.next_u64() % i)]);
    size_t n_test = std::max<size_t>(1, size_t(std::lround(opt.test_fraction * double(acc.size()))));
    n_test = std::min(n_test, acc.size() - 1);

    fs::path final_dir = fs::path(opt.out) / "objects" / job.name;
    fs::path dir = fs::path(opt.out) / "objects" / (job.name + ".tmp");
    fs::remove_all(dir);
    fs::create_directories(dir / "touches");

    std::vector<TouchRecord> recs;
    std::vector<SensorPose> poses;
    const int H = sh.calib.height, W = sh.calib.width;
    for (size_t k = 0; k < perm.size(); ++k) {
        Accepted& a = acc[perm[k]];
        bool test = k < n_test;
        if (!test && opt.randomize_train_look) {
            // Re-render the train touch with a randomised sensor look.
            Appearance look = random_look(rng);
            if (!sh.background.empty()) look.background = sh.background;
            Touch t = renderer.render(a.point, a.normal, a.params, look, rng.next_u64());
            if (t.ok) a.touch = std::move(t);
        }
        TouchRecord r = record(a.touch, int(k), test ? "test" : "train", a.params);
        write_png(dir / r.image, a.touch.image, H, W);
        recs.push_back(r);
        poses.push_back(a.touch.pose);
    }
    sh.touches += long(recs.size());

    // Collection order: a nearest-neighbour path over the surface through all
    // train and test contacts, from a random start.
    {
        std::vector<bool> used(recs.size(), false);
        size_t cur = size_t(rng.next_u64() % recs.size());
        for (size_t step = 0; step < recs.size(); ++step) {
            used[cur] = true;
            recs[cur].order = int(step);
            size_t best = cur;
            double bd = 1e300;
            for (size_t j = 0; j < recs.size(); ++j)
                if (!used[j] && dist(recs[cur].contact, recs[j].contact) < bd) {
                    bd = dist(recs[cur].contact, recs[j].contact);
                    best = j;
                }
            cur = best;
        }
        std::vector<size_t> by_order(recs.size());
        for (size_t i = 0; i < recs.size(); ++i) by_order[size_t(recs[i].order)] = i;
        for (size_t s = 1; s < by_order.size(); ++s)
            relative(poses[by_order[s - 1]], poses[by_order[s]], recs[by_order[s]]);
    }

    // Extra training touches: new contacts, never within 2 mm of a test contact.
    int extra_done = 0, extra_draws = 0;
    while (extra_done < opt.extra && extra_draws < 50 * opt.extra + 200) {
        ++extra_draws;
        Vec3 p, n;
        next_point(p, n);
        TouchParams tp = draw_params();
        Appearance look = opt.randomize_train_look ? random_look(rng) : Appearance{};
        if (!sh.background.empty()) look.background = sh.background;
        Touch t = renderer.render(p, n, tp, look, rng.next_u64());
        if (!t.ok) {
            sh.rejected++;
            continue;
        }
        bool near_test = false;
        for (size_t k = 0; k < n_test; ++k) near_test = near_test || dist(recs[k].contact, t.contact) < 2.0;
        if (near_test) continue;
        TouchRecord r = record(t, int(recs.size()), "extra", tp);
        write_png(dir / r.image, t.image, H, W);
        recs.push_back(r);
        ++extra_done;
        sh.touches++;
    }

    write_png(dir / "background.png", renderer.background_frame(plain), H, W);
    io::save_mesh_ply((dir / "mesh.ply").string(), mesh);
    write_points_csv((dir / "points.csv").string(), o.points);
    write_touches_csv((dir / "touches.csv").string(), recs);
    write_object_json((dir / "object.json").string(), o);
    fs::remove_all(final_dir);
    fs::rename(dir, final_dir);
    return o;
}

ObjectRecord read_built_object(const fs::path& dir) {
    std::ifstream f(dir / "object.json");
    json j = json::parse(f, nullptr, false);
    if (j.is_discarded()) throw Error((dir / "object.json").string() + ": not valid JSON (delete the folder to rebuild)");
    ObjectRecord o;
    o.name = j.value("name", "");
    o.subset = j.value("subset", "");
    o.dn_share = j.value("dn_share", 0.0);
    return o;
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
        std::string scale, more;
        in >> s.source >> scale >> more;
        if (!more.empty()) throw Error(path + ":" + std::to_string(lineno) + ": expected '<source> [scale_mm]'");
        if (!scale.empty()) {
            char* end = nullptr;
            double v = std::strtod(scale.c_str(), &end);
            if (*end || !(v > 0) || !std::isfinite(v))
                throw Error(path + ":" + std::to_string(lineno) + ": scale '" + scale + "' is not a positive number");
            s.scale_mm = v;
        }
        if (s.source.rfind("shape:", 0) != 0 && fs::path(s.source).is_relative()) s.source = (base / s.source).string();
        out.push_back(s);
    }
    if (out.empty()) throw Error(path + ": no objects listed");
    return out;
}

BuildReport build_dataset(const std::vector<ObjectSource>& objects, const BuildOptions& opt) {
    auto t0 = std::chrono::steady_clock::now();
    if (objects.empty()) throw Error("synth: no objects given");
    if (opt.contacts < 2) throw Error("synth: --contacts must be at least 2 (train and test)");
    if (opt.n_points < 1) throw Error("synth: --n-points must be positive");
    if (opt.max_tilt_deg < 0 || opt.max_tilt_deg > 10) throw Error("synth: tilt must be within 0..10 degrees");
    if (!(opt.press_min_mm > 0) || opt.press_max_mm < opt.press_min_mm)
        throw Error("synth: press depth range must be positive and ordered");

    Calibration calib = load_calibration(opt.calibration.empty() ? default_calibration_path() : opt.calibration);
    std::vector<float> background;
    if (!opt.background.empty()) {
        cv::Mat bg = cv::imread(opt.background, cv::IMREAD_COLOR);
        if (bg.empty()) throw Error(opt.background + ": cannot read the background image");
        if (bg.rows != calib.height || bg.cols != calib.width)
            cv::resize(bg, bg, cv::Size(calib.width, calib.height), 0, 0, cv::INTER_AREA);
        background.assign(size_t(calib.height) * size_t(calib.width) * 3, 0);
        for (int y = 0; y < bg.rows; ++y)
            for (int x = 0; x < bg.cols; ++x)
                for (int c = 0; c < 3; ++c)
                    background[(size_t(y) * size_t(bg.cols) + size_t(x)) * 3 + size_t(c)] = bg.at<cv::Vec3b>(y, x)[c];
    }

    fs::create_directories(fs::path(opt.out) / "objects");
    fs::path stamp = fs::path(opt.out) / "build.json";
    std::string want_opts = options_json(opt);
    if (fs::exists(stamp)) {
        std::ifstream f(stamp);
        std::string have((std::istreambuf_iterator<char>(f)), {});
        if (trim(have) != want_opts)
            throw Error(opt.out + ": was built with other options (build.json); use another folder or delete it");
    } else {
        write_file_atomic(stamp.string(), want_opts + "\n");
    }

    std::vector<Job> jobs;
    std::map<std::string, int> seen_names;
    for (size_t i = 0; i < objects.size(); ++i) {
        Job j{int(i), objects[i], object_name(objects[i].source)};
        if (j.name.empty()) throw Error(objects[i].source + ": cannot name the object");
        if (seen_names[j.name]++) j.name += "_" + std::to_string(seen_names[j.name]);
        jobs.push_back(j);
    }

    Shared sh{opt, calib, background};
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
                if (opt.view && !fs::exists(dir / "view.xyz")) {
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

    // Object-level 7:3 split, stratified by subset, from the dataset seed.
    Dataset d;
    d.root = opt.out;
    d.seed = opt.seed;
    d.n_points = opt.n_points;
    d.sensor.height = calib.height;
    d.sensor.width = calib.width;
    d.sensor.mm_per_px = opt.mm_per_px ? *opt.mm_per_px : calib.mm_per_px;
    d.sensor.calibration = opt.calibration.empty() ? "objectfolder_gelsight_calib" : fs::path(opt.calibration).stem().string();
    io::SplitMix64 split_rng(opt.seed ^ 0x5EEDull);
    for (const char* subset : {"non-uniform", "uniform"}) {
        std::vector<size_t> idx;
        for (size_t i = 0; i < built.size(); ++i)
            if (built[i].subset == subset) idx.push_back(i);
        for (size_t i = idx.size(); i > 1; --i) std::swap(idx[i - 1], idx[size_t(split_rng.next_u64() % i)]);
        size_t n_unseen = size_t(std::lround(opt.unseen_fraction * double(idx.size())));
        if (idx.size() >= 2) n_unseen = std::clamp<size_t>(n_unseen, 1, idx.size() - 1);
        else n_unseen = 0;
        for (size_t k = 0; k < idx.size(); ++k) built[idx[k]].object_split = k < n_unseen ? "unseen" : "seen";
    }
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
