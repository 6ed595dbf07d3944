// One object of a `vtloc synth` dataset (docs/dataset.md): mesh, cloud,
// contacts, touches, collection order and files.
#include "engine/sim/object_builder.h"
#include "engine/sim/symmetry.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <opencv2/core.hpp>

#include "base/error.h"
#include "engine/io/image_mat.h"
#include "engine/io/mesh_formats.h"
#include "engine/io/splitmix64.h"
#include "engine/sim/shapes.h"
#include "engine/sim/touch_renderer.h"
#include "engine/sim/uniformity.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace vtloc::sim {

namespace {

// Mesh scaled so its largest bounding-box side is scale_mm, centred on its box.
io::TriangleMesh scaled(io::TriangleMesh m, double scale_mm, double* f_out = nullptr, Vec3d* centre_out = nullptr) {
    const io::MeshBounds b = io::bounds(m);
    const std::array<double, 3> c = b.centre();
    const double f = scale_mm / b.largest_side();
    if (f_out) *f_out = f;
    if (centre_out) *centre_out = {c[0], c[1], c[2]};
    for (size_t i = 0; i < m.vertex_count(); ++i)
        for (int k = 0; k < 3; ++k) {
            float& v = m.positions[i * 3 + size_t(k)];
            v = float((v - c[size_t(k)]) * f);
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
    io::write_png(p.string(), m);
}

// The touch's frame, and with --indentation its indentation map beside it
// (micrometres in 16 bits: up to 65 mm, far beyond any press).
void write_touch(const fs::path& dir, const TouchRecord& r, const Touch& t, int h, int w, bool indentation) {
    write_png(dir / r.image, t.image, h, w);
    if (!indentation) return;
    cv::Mat d(h, w, CV_16UC1);
    for (int i = 0; i < h * w; ++i)
        d.ptr<uint16_t>()[i] = uint16_t(std::clamp(std::lround(double(t.indentation_mm[size_t(i)]) * 1000.0), 0L, 65535L));
    fs::path p = dir / r.image;
    p.replace_extension(".depth.png");
    io::write_png(p.string(), d);
}

}  // namespace

namespace {

// The object's mesh, scaled so its largest side is the given or drawn size (mm).
// A procedural shape's symmetry group moves with it, a mesh file's listed half turn is checked
// (`symmetry`; else none).
io::TriangleMesh object_mesh(const Job& job, io::SplitMix64& rng, double& scale, Symmetry* symmetry = nullptr) {
    io::TriangleMesh mesh;
    const bool shape = job.src.source.rfind("shape:", 0) == 0;
    if (shape) {
        mesh = make_shape(job.name);
        scale = job.src.scale_mm ? *job.src.scale_mm : shape_scale_mm(job.name);
    } else {
        mesh = io::load_mesh(job.src.source);
        scale = job.src.scale_mm ? *job.src.scale_mm : uniform(rng, 50, 250);
    }
    if (!(scale >= 1 && scale <= 10000))
        throw Error(job.src.source + ": scale " + std::to_string(scale) + " mm is outside 1..10000");
    double f = 1;
    Vec3d centre{};
    io::TriangleMesh out = scaled(std::move(mesh), scale, &f, &centre);
    if (symmetry && shape) *symmetry = scaled_symmetry(shape_symmetry(job.name), f, centre);
    if (symmetry && job.src.half_turn) {  // about the scaled mesh's bounding-box centre, the origin
        *symmetry = Symmetry{};
        symmetry->order = 2;
        symmetry->axis = {job.src.half_turn == 'x' ? 1.0 : 0.0, job.src.half_turn == 'y' ? 1.0 : 0.0,
                          job.src.half_turn == 'z' ? 1.0 : 0.0};
        const double r = symmetry_residual_mm(*symmetry, out, 400);
        if (!(r <= 0.2))
            throw Error(job.src.source + ": half-turn:" + std::string(1, job.src.half_turn) + " does not hold: the turned mesh lies " +
                        std::to_string(r) + " mm off itself (at most 0.2)");
    }
    return out;
}

// Contact draws: area-weighted surface samples in batches of 256, each rendered
// with its own spin, tilt and press.
struct Draws {
    const io::TriangleMesh& mesh;
    const std::string& source;
    const BuildOptions& opt;
    io::SplitMix64& rng;
    uint64_t seed;
    HostTensor pool;
    int64_t at = 0;

    void next_point(Vec3& p, Vec3& n) {
        if (at >= (pool.shape.empty() ? 0 : pool.shape[0])) {
            pool = io::sample_surface(mesh, 256, seed++, source);
            at = 0;
        }
        const float* q = &pool.data[size_t(at++) * 6];
        p = {q[0], q[1], q[2]};
        n = {q[3], q[4], q[5]};
    }
    TouchParams params() {
        TouchParams tp;
        tp.press_mm = uniform(rng, opt.press_min_mm, opt.press_max_mm);
        tp.spin_deg = uniform(rng, 0, 360);
        tp.tilt_deg = uniform(rng, 0, opt.max_tilt_deg);
        tp.tilt_dir_deg = uniform(rng, 0, 360);
        return tp;
    }
};

struct Accepted {
    Touch touch;
    TouchParams params;
    Vec3 point, normal;  // the draw (the contact is its projection)
};

// Up to opt.contacts reachable contacts at least min_separation_mm apart.
std::vector<Accepted> draw_contacts(const Job& job, Shared& sh, TouchRenderer& renderer, const Appearance& plain,
                                    Draws& draws) {
    const BuildOptions& opt = sh.opt;
    std::vector<Accepted> acc;
    const int want = opt.contacts;
    const int max_draws = 50 * std::max(want, 1) + 200;
    int n = 0;
    while (int(acc.size()) < want && n < max_draws) {
        ++n;
        Vec3 p, nrm;
        draws.next_point(p, nrm);
        TouchParams tp = draws.params();
        Touch t = renderer.render(p, nrm, tp, plain, draws.rng.next_u64());
        if (!t.ok) {
            sh.rejected++;
            continue;
        }
        bool close = false;
        for (const auto& a : acc) close = close || dist(a.touch.contact, t.contact) < opt.min_separation_mm;
        if (close) continue;
        acc.push_back({std::move(t), tp, p, nrm});
    }
    if (acc.size() < 2) throw Error(job.src.source + ": no reachable contacts found (" + std::to_string(n) + " draws)");
    if (int(acc.size()) < want) {
        std::lock_guard<std::mutex> lock(sh.mu);
        sh.notes.push_back(job.name + ": " + std::to_string(acc.size()) + " of " + std::to_string(want) +
                           " contacts (the rest unreachable or too close)");
    }
    return acc;
}

// Collection order: a nearest-neighbour path over the surface through all train
// and test contacts from a random start, and the sensor motion along it.
void collection_order(std::vector<TouchRecord>& recs, const std::vector<SensorPose>& poses, io::SplitMix64& rng) {
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
    for (size_t s = 1; s < by_order.size(); ++s) relative(poses[by_order[s - 1]], poses[by_order[s]], recs[by_order[s]]);
}

// Extra training touches: new contacts, never within 2 mm of a test contact.
// Each contact gets extra_views renders in a row (fewer only for the last, when
// extra is not a multiple), each with its own spin, press, tilt and look, so that
// training sees one place under the nuisances a network must learn to ignore; a
// contact where any of them fails is dropped whole.
void extra_touches(Shared& sh, TouchRenderer& renderer, Draws& draws, size_t n_test, const fs::path& dir,
                   std::vector<TouchRecord>& recs) {
    const BuildOptions& opt = sh.opt;
    int done = 0, n = 0;
    while (done < opt.extra && n < 50 * opt.extra + 200) {
        Vec3 p, nrm;
        draws.next_point(p, nrm);
        const int views = std::min(opt.extra_views, opt.extra - done);
        std::vector<std::pair<Touch, TouchParams>> group;
        for (int v = 0; v < views; ++v) {
            ++n;
            TouchParams tp = draws.params();
            Appearance look = opt.randomize_train_look ? random_look(draws.rng) : Appearance{};
            if (!sh.background.empty()) look.background = sh.background;
            Touch t = renderer.render(p, nrm, tp, look, draws.rng.next_u64());
            if (!t.ok) {
                sh.rejected++;
                break;
            }
            bool near_test = false;
            for (size_t k = 0; k < n_test; ++k) near_test = near_test || dist(recs[k].contact, t.contact) < 2.0;
            if (near_test) break;
            group.push_back({std::move(t), tp});
        }
        if (int(group.size()) < views) continue;
        for (auto& [t, tp] : group) {
            TouchRecord r = record(t, int(recs.size()), "extra", tp);
            write_touch(dir, r, t, sh.calib.height, sh.calib.width, opt.indentation);
            recs.push_back(r);
            ++done;
            sh.touches++;
        }
    }
}

}  // namespace

// Builds one object into objects/<name>.tmp, then renames it into place.
ObjectRecord build_object(const Job& job, Shared& sh) {
    const BuildOptions& opt = sh.opt;
    io::SplitMix64 rng(opt.seed * 0x9E3779B97F4A7C15ull + uint64_t(job.index) * 0xD1B54A32D192ED03ull + 1);
    double scale = 0;
    Symmetry symmetry;
    const io::TriangleMesh mesh = object_mesh(job, rng, scale, &symmetry);

    ObjectRecord o;
    o.symmetry = symmetry;
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
    const uint64_t draw_seed = rng.next_u64();
    Draws draws{mesh, job.src.source, opt, rng, draw_seed, HostTensor{}, 0};
    std::vector<Accepted> acc = draw_contacts(job, sh, renderer, plain, draws);

    // 7:3 split (a seeded shuffle), test contacts first in id order.
    std::vector<size_t> perm(acc.size());
    std::iota(perm.begin(), perm.end(), 0);
    for (size_t i = perm.size(); i > 1; --i) std::swap(perm[i - 1], perm[size_t(rng.next_u64() % i)]);
    size_t n_test = std::max<size_t>(1, size_t(std::lround(opt.test_fraction * double(acc.size()))));
    n_test = std::min(n_test, acc.size() - 1);

    const fs::path final_dir = fs::path(opt.out) / "objects" / job.name;
    const fs::path dir = fs::path(opt.out) / "objects" / (job.name + ".tmp");
    fs::remove_all(dir);
    fs::create_directories(dir / "touches");

    std::vector<TouchRecord> recs;
    std::vector<SensorPose> poses;
    const int H = sh.calib.height, W = sh.calib.width;
    for (size_t k = 0; k < perm.size(); ++k) {
        Accepted& a = acc[perm[k]];
        const bool test = k < n_test;
        if (!test && opt.randomize_train_look) {  // re-rendered with a randomised sensor look
            Appearance look = random_look(rng);
            if (!sh.background.empty()) look.background = sh.background;
            Touch t = renderer.render(a.point, a.normal, a.params, look, rng.next_u64());
            if (t.ok) a.touch = std::move(t);
        }
        TouchRecord r = record(a.touch, int(k), test ? "test" : "train", a.params);
        write_touch(dir, r, a.touch, H, W, opt.indentation);
        recs.push_back(r);
        poses.push_back(a.touch.pose);
    }
    sh.touches += long(recs.size());
    collection_order(recs, poses, rng);
    extra_touches(sh, renderer, draws, n_test, dir, recs);

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


}  // namespace vtloc::sim
