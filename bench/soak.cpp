// vtloc-soak: thousands of localisations on one context through the public
// API, mixing objects, image sizes, batch sizes, N, K, symmetry and
// sequences. Every output must be bit-identical to the first run of the same
// case; the bytes malloc holds, host RSS and the context's GPU memory are sampled
// after every run and must stay flat after the warm-up (each case's first run
// builds its graph).
//   vtloc-soak [--model M] [--runs 10000] [--warmup W] [--cases N] [--json FILE]
//              [--png FILE] [--max-heap-drift-mib 0.25] [--max-drift-mib 8]
// --cases N runs the first N of the mixed cases only (the leak check's own test:
// a first run compiles each case's shaders, most of a short run on a cold machine).
//   vtloc-soak --plot-from SOAK.json --png FILE    (redraw a run's picture)
// The warm-up (default: the larger of one pass over the cases and a tenth of
// the runs) is left out of the flatness checks: glibc's heap takes a few
// steps of 1-6 MiB in the first ~200 runs as it settles, then stays put.
// glibc's mmap threshold is pinned at its 128 KiB default: left dynamic, it
// rises to the size of each large block freed (a batch's images and
// preprocessed frames, up to 4 MiB per run), after which such blocks come from
// the heap and fragment it. That creep is bounded (measured: +4.7 MiB over the
// first 2,000 runs, flat from 2,000 to 6,000) but would cover a leak of the same
// size in a 500-run check; pinned, the slope is -0.1 MiB per 1,000 runs.
// Exit 0 when outputs repeat exactly, GPU memory does not move after the
// warm-up, the bytes malloc has handed out grow less than --max-heap-drift-mib
// (the leak check: flat to 0.003 MiB over 250 runs) and host RSS less than
// --max-drift-mib (a looser bound on fragmentation: RSS alone moved by 1.6 MiB
// over 250 runs with no byte leaked, once under ctest -j2).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string>
#include <unistd.h>
#include <vector>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <nlohmann/json.hpp>
#include <vtloc/vtloc.h>

#include "base/atomic_write.h"
#include "base/shipped.h"
#include "bench/probe.h"
#include "bench/soak_plot.h"

namespace api = vtloc::api;

namespace {

// One input combination, run again and again.
struct Case {
    std::string name;
    int object = 0;
    std::vector<int> images;  // indices into the image set; >1 = a batch
    bool sequence = false;
    api::LocalizeOptions opt;
};

double rss_mib() {
    std::ifstream f("/proc/self/statm");
    long pages_total = 0, pages_rss = 0;
    f >> pages_total >> pages_rss;
    return double(pages_rss) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

// Bytes malloc has handed out and not had back (arena + mmapped blocks): a leak
// raises it however the heap is laid out, where RSS also moves with glibc's
// fragmentation and trimming (steps of 1-2 MiB long after the warm-up).
double heap_in_use_mib() {
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
    const struct mallinfo2 m = mallinfo2();
    return double(m.uordblks + m.hblkhd) / (1024.0 * 1024.0);
#else
    return std::nan("");  // no count: the heap check is skipped (and says so)
#endif
}

// FNV-1a over every output byte that a user reads.
struct Hash {
    uint64_t h = 1469598103934665603ull;
    void bytes(const void* p, size_t n) {
        auto* b = static_cast<const uint8_t*>(p);
        for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
    }
    template <class T> void vec(const std::vector<T>& v) { bytes(v.data(), v.size() * sizeof(T)); }
    void touch(const api::TouchResult& r) {
        bytes(r.contact.data(), sizeof r.contact);
        for (const auto& c : r.iterates) bytes(c.data(), sizeof c);
        vec(r.topk_index);
        vec(r.topk_score);
        vec(r.heatmap);
        if (r.alignment) bytes(&*r.alignment, sizeof(float));
    }
};

api::PointCloud sphere_cloud(int n, double radius) {
    api::PointCloud c;
    const double golden = M_PI * (3 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
        double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - z * z), a = golden * i;
        double p[3] = {r * std::cos(a), r * std::sin(a), z};
        for (double v : p) c.xyz.push_back(float(radius * v)), c.normals.push_back(float(v));
    }
    return c;
}

// A box's faces, sampled on a grid (no normals: estimated at encode).
api::PointCloud box_cloud(int per_face, double a, double b, double c) {
    api::PointCloud out;
    const int g = std::max(2, int(std::sqrt(double(per_face))));
    const double half[3] = {a / 2, b / 2, c / 2};
    for (int axis = 0; axis < 3; ++axis)
        for (int side = -1; side <= 1; side += 2)
            for (int i = 0; i < g; ++i)
                for (int j = 0; j < g; ++j) {
                    double p[3];
                    p[axis] = side * half[axis];
                    p[(axis + 1) % 3] = (2.0 * (i + 0.5) / g - 1) * half[(axis + 1) % 3];
                    p[(axis + 2) % 3] = (2.0 * (j + 0.5) / g - 1) * half[(axis + 2) % 3];
                    for (double v : p) out.xyz.push_back(float(v));
                }
    return out;
}

// The shipped touches, and resized/cropped copies of them (other sensors' sizes).
std::vector<api::TactileImage> image_set(const std::string& dir) {
    std::vector<api::TactileImage> out;
    for (const char* f : {"plate_test0_touch.png", "touch_01.png", "touch_02.png", "touch_03.png"})
        out.push_back(api::load_tactile_image(dir + "/" + f));
    out.push_back(api::rescale_tactile_image(out[0], 0.1245, 0.0622));  // 2x: a finer sensor
    out.push_back(api::rescale_tactile_image(out[1], 0.1, 0.13));       // smaller frame
    api::TactileImage crop;  // a square crop of the first touch
    crop.height = crop.width = 96;
    for (int y = 0; y < 96; ++y)
        for (int x = 0; x < 96; ++x)
            for (int k = 0; k < 3; ++k)
                crop.rgb.push_back(out[0].rgb[(size_t(y + 12) * out[0].width + x + 32) * 3 + k]);
    out.push_back(crop);
    return out;
}

std::vector<Case> make_cases(int n_objects, int n_images) {
    std::vector<Case> cases;
    const int iters[] = {0, 4, 16, 32}, topk[] = {1, 5, 8};
    int k = 0;
    for (int o = 0; o < n_objects; ++o)
        for (int v = 0; v < 6; ++v, ++k) {
            Case c;
            c.object = o;
            c.opt.iters = iters[k % 4];
            c.opt.top_k = topk[k % 3];
            c.opt.gma = k % 5 != 0;
            if (k % 4 == 1) c.opt.symmetry = api::Symmetry{{0, 0, 0}, {0, 0, 1}, 3 + k % 3};
            const int first = k % n_images;
            if (v == 0 || v == 3) c.images = {first};
            else if (v == 1) c.images = {first, (first + 1) % n_images};  // mixed sizes: two runs
            else if (v == 2) c.images = {0, 1, 2, 3};                      // one size: one batch
            else if (v == 4) c.images = {1, 2, 3, 1, 2, 3, 1, 2, 3, 1, 2, 3, 1, 2, 3, 1};  // batch 16
            else c.images = {1, 2, 3}, c.sequence = true;
            char name[96];
            std::snprintf(name, sizeof name, "obj%d/%s%zu/N%d/K%d%s%s", o, c.sequence ? "seq" : "batch",
                          c.images.size(), c.opt.iters, c.opt.top_k, c.opt.gma ? "" : "/nogma",
                          c.opt.symmetry ? "/sym" : "");
            c.name = name;
            cases.push_back(c);
        }
    return cases;
}

// fresh: the window runs on a tracker made from the object's by with_options (one host thread:
// the same estimate, bit for bit) and dropped after it: its step graphs, on the device tables
// it shares with the object's tracker, are made and given back each time.
uint64_t run_case(api::Model& model, const std::vector<api::Object>& objects, std::vector<api::Tracker>& trackers,
                  const std::vector<api::TactileImage>& images, const Case& c, size_t& touches, bool fresh) {
    std::vector<api::TactileImage> batch;
    for (int i : c.images) batch.push_back(images[size_t(i)]);
    Hash h;
    if (c.sequence) {
        // A tracker window: the touches' heat-maps as its network terms, a fixed
        // motion (10 degrees about the axis and a shift) between them.
        const api::Object& obj = objects[size_t(c.object)];
        const std::vector<api::TouchResult> rs = model.localize(obj, batch, c.opt);
        std::vector<const api::TouchResult*> terms;
        for (const auto& t : rs) h.touch(t), terms.push_back(&t);
        api::Motion m;
        const double a = 10 * M_PI / 180;
        m.R = {std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1};
        m.t = {1.5, -0.5, 0.25};
        api::Tracker& base = trackers[size_t(c.object)];
        std::optional<api::Tracker> one;
        if (fresh) {
            api::TrackerOptions o = base.options();
            o.threads = 1;
            one.emplace(base.with_options(o));
        }
        const api::TrackerEstimate e = (one ? *one : base).evaluate_window(std::vector<api::Motion>(batch.size() - 1, m), terms, &obj);
        h.vec(e.heatmap);
        h.vec(e.sample_belief);
        h.bytes(e.contact.data(), sizeof e.contact);
        h.bytes(e.pose.R.data(), sizeof e.pose.R);
    } else {
        for (const auto& t : model.localize(objects[size_t(c.object)], batch, c.opt)) h.touch(t);
    }
    touches += batch.size();
    return h.h;
}

// RSS slope and drift over the runs after the warm-up (MiB per run; slope * runs).
struct Fit {
    double slope = 0, drift = 0;
};
Fit line_fit(const std::vector<double>& y, size_t from) {
    Fit f;
    if (y.size() < from + 2) return f;
    std::vector<double> x(y.size() - from);
    for (size_t i = 0; i < x.size(); ++i) x[i] = double(from + i);
    f.slope = vtloc::bench::slope(x, {y.begin() + long(from), y.end()});
    f.drift = f.slope * double(x.size());
    return f;
}

int usage() {
    std::fprintf(stderr, "usage: vtloc-soak [--model M] [--runs N] [--warmup W] [--cases N] [--json FILE] [--png FILE] [--max-heap-drift-mib X] [--max-drift-mib X]\n");
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
#ifdef __GLIBC__
    mallopt(M_MMAP_THRESHOLD, 128 * 1024);  // see the header: measure leaks, not the allocator's policy
#endif
    std::string model_path;  // default: the shipped model, found as the CLI finds it
    std::string json_path, png_path, plot_from;
    long runs = 10000, warmup_arg = -1, leak_bytes = 0, n_cases = 0;
    double max_drift = 8.0, max_heap_drift = 0.25;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        if (i + 1 >= argc) return usage();
        if (a == "--model") model_path = argv[++i];
        else if (a == "--runs") runs = std::atol(argv[++i]);
        else if (a == "--warmup") warmup_arg = std::atol(argv[++i]);
        else if (a == "--cases") n_cases = std::atol(argv[++i]);
        else if (a == "--json") json_path = argv[++i];
        else if (a == "--png") png_path = argv[++i];
        else if (a == "--plot-from") plot_from = argv[++i];
        else if (a == "--max-drift-mib") max_drift = std::atof(argv[++i]);
        else if (a == "--max-heap-drift-mib") max_heap_drift = std::atof(argv[++i]);
        else if (a == "--leak-bytes-per-run") leak_bytes = std::atol(argv[++i]);  // the check's own test
        else return usage();
    }
    if (runs < 1 || n_cases < 0) return usage();
    try {
        if (!plot_from.empty()) {
            std::ifstream in(plot_from);
            const nlohmann::json j = nlohmann::json::parse(in);
            if (png_path.empty()) return usage();
            vtloc::bench::plot_soak(png_path, j.at("rss_mib").get<std::vector<double>>(),
                                    j.at("gpu_mib").get<std::vector<double>>(), j.at("warmup_runs").get<size_t>(),
                                    j.at("rss_slope_mib_per_run").get<double>());
            return 0;
        }
        const std::filesystem::path data =
            vtloc::find_shipped_dir(vtloc::shipped_dir_candidates(vtloc::current_executable(), "", VTLOC_SOURCE_DIR));
        if (model_path.empty()) model_path = (data / vtloc::kDefaultModel).string();
        api::Context ctx;
        api::Model model(ctx, model_path);
        const std::string ex = (data / "examples").string();
        std::vector<api::Object> objects;
        objects.push_back(model.encode_object(ex + "/plate_test0.ply", ex + "/plate_test0_candidates.csv"));
        objects.push_back(model.encode_object(ex + "/mug.glb", ex + "/mug_candidates.csv"));
        objects.push_back(model.encode_object(sphere_cloud(1500, 30)));
        objects.push_back(model.encode_object(box_cloud(400, 80, 40, 20)));
        std::vector<api::Tracker> trackers;  // one per object, from its cloud (stateless windows)
        api::TrackerOptions to;
        to.hypotheses = 20000;
        for (const api::Object& o : objects) trackers.emplace_back(ctx, o.cloud(), to);
        const std::vector<api::TactileImage> images = image_set(ex);
        std::vector<Case> cases = make_cases(int(objects.size()), int(images.size()));
        if (n_cases > 0 && size_t(n_cases) < cases.size()) cases.resize(size_t(n_cases));

        std::vector<uint64_t> first(cases.size(), 0);
        std::vector<double> rss, heap, gpu;
        std::vector<std::vector<char>> leaked;
        size_t touches = 0, mismatches = 0;
        // Every case's first run builds its graph: always inside the warm-up.
        const size_t warmup = std::max<size_t>(cases.size(), warmup_arg >= 0 ? size_t(warmup_arg) : size_t(runs) / 10);
        if (warmup + 2 > size_t(runs)) throw std::runtime_error("--runs must exceed the warm-up (" + std::to_string(warmup) + " runs) by 2");
        uint64_t order = 0x9e3779b97f4a7c15ull;
        const auto t0 = std::chrono::steady_clock::now();
        for (long r = 0; r < runs; ++r) {
            // First pass in order (warm-up), then a fixed pseudo-random order.
            size_t ci = size_t(r);
            if (size_t(r) >= cases.size()) {
                order ^= order << 13, order ^= order >> 7, order ^= order << 17;
                ci = size_t(order % cases.size());
            }
            const uint64_t h = run_case(model, objects, trackers, images, cases[ci], touches,
                                      size_t(r) >= cases.size() && r % 2 == 1);  // the first pass makes the object trackers' graphs
            if (size_t(r) < cases.size()) first[ci] = h;
            else if (h != first[ci]) {
                if (++mismatches <= 5) std::fprintf(stderr, "run %ld: %s differs from its first run\n", r, cases[ci].name.c_str());
            }
            if (leak_bytes > 0) {  // held to the end, as a leak would be; touched, so RSS sees it too
                leaked.emplace_back(size_t(leak_bytes), char(1));
            }
            rss.push_back(rss_mib());
            heap.push_back(heap_in_use_mib());
            gpu.push_back(double(ctx.memory_in_use()) / (1024.0 * 1024.0));
            if (r % 1000 == 999) std::fprintf(stderr, "%ld runs, RSS %.1f MiB, GPU %.1f MiB\n", r + 1, rss.back(), gpu.back());
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const auto validation = ctx.take_validation_messages();

        const Fit rf = line_fit(rss, warmup), hf = line_fit(heap, warmup), gf = line_fit(gpu, warmup);
        double gpu_moved = 0, rss_lo = 1e300, rss_hi = 0;
        for (size_t i = std::min(warmup, gpu.size()); i < gpu.size(); ++i) {
            gpu_moved = std::max(gpu_moved, std::abs(gpu[i] - gpu[warmup]));
            rss_lo = std::min(rss_lo, rss[i]), rss_hi = std::max(rss_hi, rss[i]);
        }
        // A leak is growth: a falling RSS (glibc handing pages back, -1.5 MiB over 250
        // runs seen under ctest -j2) passes.
        const bool heap_ok = !(hf.drift >= max_heap_drift);  // NaN: no count on this C library
        const bool ok = mismatches == 0 && gpu_moved == 0 && rf.drift < max_drift && heap_ok && validation.empty();
        std::printf("vtloc-soak: %ld runs (%zu touches) of %zu cases on %s, model %s, %.1f s\n", runs, touches,
                    cases.size(), ctx.device().name.c_str(), model.info().name.c_str(), seconds);
        std::printf("  outputs bit-identical to each case's first run: %s (%zu differ)\n", mismatches ? "NO" : "yes",
                    mismatches);
        std::printf("  host RSS: %.2f MiB at the start, %.2f at the end of the warm-up (run %zu); after it %.2f .. %.2f MiB,\n"
                    "            slope %.3g MiB per 1000 runs, drift %.3f MiB over %zu runs (allowed %.2f)\n",
                    rss.front(), rss[warmup], warmup, rss_lo, rss_hi, 1000 * rf.slope, rf.drift, rss.size() - warmup, max_drift);
        std::printf("  heap in use: %.2f MiB at the end of the warm-up, %.2f at the end; slope %.3g MiB per 1000 runs,\n"
                    "            drift %.3f MiB (allowed %.2f)\n",
                    heap[warmup], heap.back(), 1000 * hf.slope, hf.drift, max_heap_drift);
        // One verdict per check, so a test can tell which one failed.
        std::printf("  checks: outputs %s, GPU memory %s, heap %s, RSS %s, validation %s\n", mismatches ? "FAIL" : "pass",
                    gpu_moved == 0 ? "pass" : "FAIL", std::isnan(hf.drift) ? "unavailable" : heap_ok ? "pass" : "FAIL",
                    rf.drift < max_drift ? "pass" : "FAIL", validation.empty() ? "pass" : "FAIL");
        std::printf("  GPU memory after warm-up: %.2f MiB, moved %.3f MiB\n", gpu.empty() ? 0 : gpu.back(), gpu_moved);
        std::printf("  validation messages: %zu\n", validation.size());
        std::printf("%s\n", ok ? "PASS" : "FAIL");
        if (!json_path.empty()) {
            nlohmann::json j = {{"runs", runs}, {"touches", touches}, {"cases", cases.size()}, {"seconds", seconds},
                                {"device", ctx.device().name}, {"model", model.info().name}, {"warmup_runs", warmup},
                                {"mismatches", mismatches}, {"rss_mib", rss}, {"gpu_mib", gpu},
                                {"rss_slope_mib_per_run", rf.slope}, {"rss_drift_mib", rf.drift}, {"heap_mib", heap},
                                {"heap_drift_mib", hf.drift},
                                {"gpu_slope_mib_per_run", gf.slope}, {"gpu_moved_mib", gpu_moved},
                                {"validation_messages", validation.size()}, {"pass", ok}};
            vtloc::write_file_atomic(json_path, j.dump() + "\n");
        }
        if (!png_path.empty()) vtloc::bench::plot_soak(png_path, rss, gpu, warmup, rf.slope);
        return ok ? 0 : 1;
    } catch (const std::exception& e) {  // api::Error, or a file the soak writes
        std::fprintf(stderr, "vtloc-soak: %s\n", e.what());
        return 1;
    }
}
