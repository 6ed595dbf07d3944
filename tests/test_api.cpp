// The public API (<vtloc/vtloc.h>): results against the engine's runner,
// batches and sequences, outputs, and contexts on concurrent threads.
#include <catch2/catch.hpp>
#include <atomic>
#include <cmath>
#include <exception>
#include <filesystem>
#include <optional>
#include <thread>

#include "engine/io/candidates.h"
#include "engine/io/image.h"
#include "engine/io/object.h"
#include "engine/io/ply.h"
#include "engine/model/vtloc_runner.h"
#include "engine/ops/tactile_preprocess.h"
#include "engine/safetensors.h"
#include "tests/api_test_util.h"
#include "tests/harness.h"

using namespace vtloc;

namespace {

const char* kSpec8[] = {"tactile.input", "tactile.feature", "point.cloud", "point.sa1.fps", "point.sa2.fps",
                        "point.sa1.ball.0", "point.feature", "gma.cloud", "gma.chamfer", "ilu.c", "contact",
                        "topk.index", "topk.score", "heatmap"};

api::TactileImage example_image(int n) {
    return api::load_tactile_image(test::source_path("examples/touch_0" + std::to_string(n) + ".png"));
}

// Top-left crop: a tactile image of another size.
api::TactileImage crop(const api::TactileImage& im, int h, int w) {
    api::TactileImage out{h, w, std::vector<uint8_t>(size_t(h) * size_t(w) * 3)};
    for (int y = 0; y < h; ++y)
        std::copy_n(&im.rgb[size_t(y) * size_t(im.width) * 3], size_t(w) * 3, &out.rgb[size_t(y) * size_t(w) * 3]);
    return out;
}

void check_same(const api::TouchResult& a, const api::TouchResult& b, double tol) {
    for (int i = 0; i < 3; ++i) CHECK(std::abs(a.contact[size_t(i)] - b.contact[size_t(i)]) <= tol * (1 + std::abs(b.contact[size_t(i)])));
    CHECK(a.topk_index == b.topk_index);
    REQUIRE(a.heatmap.size() == b.heatmap.size());
    for (size_t i = 0; i < a.heatmap.size(); ++i) CHECK(std::abs(a.heatmap[i] - b.heatmap[i]) <= tol);
}

}  // namespace

TEST_CASE("api: a touch through the public API equals the engine's runner", "[api]") {
    api::Context ctx(test::validated());
    api::Model model(ctx, test::tiny_model());
    const std::string mug = test::source_path("examples/mug.glb"), cands = test::source_path("examples/mug_candidates.csv");
    api::Object obj = model.encode_object(mug, cands);
    api::TactileImage image = example_image(1);
    api::LocalizeOptions opt;
    opt.keep_tensors = true;
    api::TouchResult r = model.localize(obj, image, opt);
    test::require_no_validation(ctx);

    // A context of the test's own, not the harness's process-wide one: that one
    // is destroyed during static destruction, and after the API's instance had
    // come and gone it crashed there, inside the validation layer (Debian 12).
    rt::ContextOptions ro;
    ro.validation = 1;
    rt::Context gpu(ro);
    VtlocRunner runner(WeightStore::load(test::tiny_model()), &gpu);
    HostTensor cloud = io::load_object(mug, model.info().sample_points), cand = io::load_candidates(cands);
    TouchResult want = runner.localize_once(ops::tactile_image_tensor(image.rgb.data(), image.height, image.width),
                                            cloud, &cand);
    CHECK(gpu.take_validation_messages().empty());

    REQUIRE(obj.cloud().size() == size_t(cloud.shape[0]));
    REQUIRE(obj.candidate_count() == size_t(cand.shape[0]));
    for (int i = 0; i < 3; ++i) CHECK(std::abs(r.contact[size_t(i)] - want.contact[size_t(i)]) < 1e-4);
    CHECK(r.topk_index == want.topk_index);
    REQUIRE(r.topk_point.size() == r.topk_index.size());
    for (size_t k = 0; k < r.topk_index.size(); ++k)
        for (size_t i = 0; i < 3; ++i) CHECK(r.topk_point[k][i] == cand.data[size_t(r.topk_index[k]) * 3 + i]);
    REQUIRE(r.iterates.size() == size_t(model.info().default_iters));
    for (size_t i = 0; i < 3; ++i) CHECK(std::abs(r.iterates.back()[i] - r.contact[i]) < 1e-9);
    REQUIRE(r.alignment.has_value());
    CHECK(r.heatmap.size() == obj.cloud().size());
    for (const char* name : kSpec8) {
        INFO(name);
        CHECK(std::any_of(r.tensors.begin(), r.tensors.end(), [&](const api::Tensor& t) { return t.name == name; }));
    }
}

TEST_CASE("api: a tracker's estimate, its modes climbed on the host's threads, is the same from two threads at once", "[api][threads][tracker]") {
    // The refinement spreads its modes over up to 4 threads (engine/track/tracker.cpp); with
    // the rescue always on (32 modes) two trackers at once, each on its own thread, must give
    // the estimate of one alone, bit for bit.
    const std::string potato = test::source_path("examples/potato_tour.ply");
    api::TrackerOptions o;
    o.hypotheses = 20000;
    o.rescue_fit = 0;
    const std::vector<api::Motion> window{{{1, 0, 0, 0, 1, 0, 0, 0, 1}, {6, 0, 0}},
                                          {{0.866, 0, 0.5, 0, 1, 0, -0.5, 0, 0.866}, {0, 8, 1}}};
    auto run = [&] {
        api::Context ctx;
        api::Tracker tr(ctx, potato, o);
        return tr.evaluate_window(window);
    };
    const api::TrackerEstimate want = run();
    std::vector<api::TrackerEstimate> got(2);
    std::vector<std::exception_ptr> errors(2);
    auto work = [&](size_t i) {
        try {
            got[i] = run();
        } catch (...) {
            errors[i] = std::current_exception();
        }
    };
    std::thread a(work, 0), b(work, 1);
    a.join();
    b.join();
    for (size_t i = 0; i < 2; ++i) {
        if (errors[i]) std::rethrow_exception(errors[i]);
        CHECK(got[i].contact == want.contact);
        CHECK(got[i].pose.R == want.pose.R);
        CHECK(got[i].pose.t == want.pose.t);
        CHECK(got[i].fit == want.fit);
        CHECK(got[i].sample_belief == want.sample_belief);
    }
    // A thread budget (TrackerOptions::threads) changes who climbs, not what: one thread and
    // three give the default's estimate, bit for bit; a negative budget is refused by name.
    for (int n : {1, 3}) {
        o.threads = n;
        const api::TrackerEstimate e = run();
        INFO(n << " threads");
        CHECK(e.contact == want.contact);
        CHECK(e.pose.R == want.pose.R);
        CHECK(e.pose.t == want.pose.t);
        CHECK(e.fit == want.fit);
        CHECK(e.sample_belief == want.sample_belief);
    }
    o.threads = -1;
    CHECK_THROWS_WITH(run(), Catch::Contains("threads"));
}

TEST_CASE("api: two trackers of one object on two threads at once, sharing its tables and codebook, give the results of each alone", "[api][threads][tracker]") {
    // A tracker and one with_options made share the device tables, the codebook and the binned
    // points, each made at its first use (engine/api/tracker.cpp). Both trackers' first touches
    // run at once here, so the first uses race; every result must be that of a tracker made
    // from the file alone, bit for bit.
    const std::string potato = test::source_path("examples/potato_tour.ply");
    api::TrackerOptions o;
    o.hypotheses = 5000;
    api::TrackerOptions other = o;  // the comparison's and the filter's own options differ
    other.render_weight = 0.5, other.render_press_percentile = 90, other.odometry_mm = 0.5;
    const std::vector<api::GelShape> shapes{test::gel_cap(7.5, 10.0, 0.01), test::gel_cap(6.0, 11.0, 0.0),
                                          test::gel_cap(8.0, 9.0, -0.01)};
    const std::vector<api::Motion> motions{{{1, 0, 0, 0, 1, 0, 0, 0, 1}, {6, 0, 0}},
                                           {{0.866, 0, 0.5, 0, 1, 0, -0.5, 0, 0.866}, {0, 8, 1}}};
    struct Run {
        api::TrackerEstimate online, window;
        std::vector<float> term;
    };
    auto run = [&](api::Tracker& t) {
        Run r;
        for (size_t i = 0; i < shapes.size(); ++i)
            t.add_touch(i == 0 ? std::nullopt : std::optional<api::Motion>(motions[i - 1]), nullptr, nullptr, &shapes[i]);
        r.online = t.estimate();
        r.window = t.evaluate_window(motions, {}, nullptr, {&shapes[0], &shapes[1], &shapes[2]});
        r.term = t.shape_term(shapes[1]);
        return r;
    };
    std::vector<Run> want;
    {
        api::Context alone(test::validated());
        for (const api::TrackerOptions* opt : {&o, &other}) {
            api::Tracker t(alone, potato, *opt);
            want.push_back(run(t));
        }
        test::require_no_validation(alone);
    }
    api::Context ctx(test::validated());
    api::Tracker a(ctx, potato, o);
    api::Tracker b = a.with_options(other);  // made before anything is uploaded or rendered
    for (int round = 0; round < 2; ++round) {  // the second round: all shared, already made
        INFO("round " << round);
        std::vector<Run> got(2);
        std::vector<std::exception_ptr> errors(2);
        auto work = [&](api::Tracker& t, size_t i) {
            try {
                t.reset();
                got[i] = run(t);
            } catch (...) {
                errors[i] = std::current_exception();
            }
        };
        std::thread ta(work, std::ref(a), 0), tb(work, std::ref(b), 1);
        ta.join();
        tb.join();
        for (size_t i = 0; i < 2; ++i) {
            INFO((i == 0 ? "the first tracker" : "the one with_options made"));
            if (errors[i]) std::rethrow_exception(errors[i]);
            for (auto [g, w] : {std::pair{&got[i].online, &want[i].online}, std::pair{&got[i].window, &want[i].window}}) {
                CHECK(g->sample_belief == w->sample_belief);
                CHECK(g->contact == w->contact);
                CHECK(g->pose.R == w->pose.R);
                CHECK(g->pose.t == w->pose.t);
                CHECK(g->fit == w->fit);
                CHECK(g->pose_terms == w->pose_terms);
            }
            CHECK(got[i].term == want[i].term);
        }
        CHECK(got[0].term != got[1].term);  // each scored with its own options
    }
    test::require_no_validation(ctx);
}

TEST_CASE("api: one tracker read from one thread while another adds its touches", "[api][threads][tracker]") {
    // Python releases the GIL in add_touch, so a program may read a tracker's estimate while
    // another thread adds a touch: the calls take turns (a lock), and what the reader sees is
    // always a whole state (a belief of the right size summing to 1, a touch count that only
    // grows); the writer's final estimate is that of a tracker alone, bit for bit.
    const std::string potato = test::source_path("examples/potato_tour.ply");
    api::TrackerOptions o;
    o.hypotheses = 5000;
    const std::vector<api::Motion> motions{{{1, 0, 0, 0, 1, 0, 0, 0, 1}, {6, 0, 0}},
                                           {{0.866, 0, 0.5, 0, 1, 0, -0.5, 0, 0.866}, {0, 8, 1}},
                                           {{1, 0, 0, 0, 0.866, -0.5, 0, 0.5, 0.866}, {2, -5, 0}}};
    auto tour = [&](api::Tracker& t) {
        t.add_touch(std::nullopt);
        for (const api::Motion& m : motions) t.add_touch(m);
    };
    api::Context ctx(test::validated());
    api::Tracker alone(ctx, potato, o), shared(ctx, potato, o);
    tour(alone);
    const api::TrackerEstimate want = alone.estimate();
    std::atomic<bool> done{false};
    std::exception_ptr writer_error, reader_error;
    int reads = 0, last_touches = 0;
    bool whole = true, growing = true;
    std::thread writer([&] {
        try {
            tour(shared);
        } catch (...) {
            writer_error = std::current_exception();
        }
        done = true;
    });
    std::thread reader([&] {
        try {
            while (!done || reads < 3) {
                const int n = shared.touches();
                growing = growing && n >= last_touches;
                last_touches = n;
                const std::vector<float> b = shared.belief();
                double sum = 0;
                for (float v : b) sum += v;
                if (n > 0) whole = whole && b.size() == want.sample_belief.size() * size_t(shared.n_spin()) && std::abs(sum - 1) < 1e-3;
                if (n > 0) whole = whole && shared.estimate().sample_belief.size() == want.sample_belief.size();
                whole = whole && shared.device_bytes() > 0;
                ++reads;
            }
        } catch (...) {
            reader_error = std::current_exception();
        }
    });
    writer.join();
    reader.join();
    if (writer_error) std::rethrow_exception(writer_error);
    if (reader_error) std::rethrow_exception(reader_error);
    INFO(reads << " reads");
    CHECK(whole);
    CHECK(growing);
    CHECK(shared.touches() == 4);
    const api::TrackerEstimate got = shared.estimate();
    CHECK(got.sample_belief == want.sample_belief);
    CHECK(got.contact == want.contact);
    CHECK(got.pose.R == want.pose.R);
    CHECK(got.pose.t == want.pose.t);
    test::require_no_validation(ctx);
}

TEST_CASE("api: one gel shape reader on three threads at once gives each frame's shape of one thread", "[api][threads][sensor]") {
    // The reader's GPU pipeline holds its buffers; Python releases the GIL while it reads, so
    // the reads take turns (a lock).
    api::Context ctx(test::validated());
    api::GelShapeReader reader(ctx);
    const std::vector<api::TactileImage> frames{example_image(1), example_image(2), example_image(3)};
    std::vector<api::GelShape> want;
    for (const auto& f : frames) want.push_back(reader.read(f));
    std::vector<std::vector<api::GelShape>> got(3);
    std::vector<std::exception_ptr> errors(3);
    std::vector<std::thread> threads;
    for (size_t t = 0; t < 3; ++t)
        threads.emplace_back([&, t] {
            try {
                for (int round = 0; round < 3; ++round) got[t].push_back(reader.read(frames[(t + size_t(round)) % 3]));
            } catch (...) {
                errors[t] = std::current_exception();
            }
        });
    for (auto& th : threads) th.join();
    for (size_t t = 0; t < 3; ++t) {
        if (errors[t]) std::rethrow_exception(errors[t]);
        REQUIRE(got[t].size() == 3);
        for (size_t r = 0; r < 3; ++r) {
            const api::GelShape &g = got[t][r], &w = want[(t + r) % 3];
            CHECK(g.depth_mm == w.depth_mm);  // the same device and pipelines: bit for bit
            CHECK(g.mask == w.mask);
            CHECK(g.grad_row == w.grad_row);
        }
    }
    test::require_no_validation(ctx);
}

TEST_CASE("api: four threads, a context each or one shared Model and Object, give the results of one", "[api][threads]") {
    const std::string mug = test::source_path("examples/mug.glb");
    const std::vector<api::TactileImage> images{example_image(1), example_image(2), example_image(3)};
    std::vector<api::TouchResult> want;
    api::Context shared_ctx(test::validated());
    api::Model shared_model(shared_ctx, test::tiny_model());
    const api::Object shared_obj = shared_model.encode_object(mug);
    for (auto& im : images) want.push_back(shared_model.localize(shared_obj, im));

    for (bool own_context : {true, false}) {
        INFO((own_context ? "a context per thread" : "one Model and Object shared by all threads"));
        std::vector<std::vector<api::TouchResult>> results(4);
        std::vector<std::exception_ptr> errors(4);
        std::vector<std::vector<std::string>> validation(4);  // checked after the join: Catch2 asserts on one thread only
        std::vector<std::thread> threads;
        for (int t = 0; t < 4; ++t)
            threads.emplace_back([&, t] {
                try {
                    std::optional<api::Context> ctx;
                    std::optional<api::Model> model;
                    std::optional<api::Object> obj;
                    if (own_context) {
                        ctx.emplace(test::validated());
                        model.emplace(*ctx, test::tiny_model());
                        obj.emplace(model->encode_object(mug));
                    }
                    api::Model& m = own_context ? *model : shared_model;
                    const api::Object& o = own_context ? *obj : shared_obj;
                    for (int round = 0; round < 3; ++round)
                        for (size_t i = 0; i < images.size(); ++i)
                            results[size_t(t)].push_back(m.localize(o, images[(i + size_t(t)) % images.size()]));
                    if (own_context) validation[size_t(t)] = ctx->take_validation_messages();
                } catch (...) {
                    errors[size_t(t)] = std::current_exception();
                }
            });
        for (auto& th : threads) th.join();
        for (int t = 0; t < 4; ++t) {
            if (errors[size_t(t)]) std::rethrow_exception(errors[size_t(t)]);
            CHECK(validation[size_t(t)].empty());
            REQUIRE(results[size_t(t)].size() == 9);
            for (size_t k = 0; k < 9; ++k) {
                const api::TouchResult& got = results[size_t(t)][k];
                const api::TouchResult& ref = want[(k % 3 + size_t(t)) % 3];
                CHECK(got.contact == ref.contact);  // same device, same pipelines: bit for bit
                CHECK(got.topk_index == ref.topk_index);
                CHECK(got.heatmap == ref.heatmap);
                CHECK(got.alignment == ref.alignment);
            }
        }
    }
    test::require_no_validation(shared_ctx);
}

TEST_CASE("api: batches of mixed sizes, sequences and the CPU backend", "[api]") {
    api::Context ctx(test::validated());
    api::Model model(ctx, test::tiny_model());
    api::Object obj = model.encode_object(test::source_path("examples/mug.glb"),
                                          test::source_path("examples/mug_candidates.csv"));
    std::vector<api::TactileImage> images{example_image(1), crop(example_image(2), 90, 100), example_image(3)};
    std::vector<api::TouchResult> batch = model.localize(obj, images);
    REQUIRE(batch.size() == 3);
    for (size_t i = 0; i < images.size(); ++i) check_same(batch[i], model.localize(obj, images[i]), 1e-6);

    api::LocalizeOptions cpu;
    cpu.backend = api::Backend::Cpu;
    check_same(model.localize(obj, images[0], cpu), batch[0], 2e-3);

    test::require_no_validation(ctx);
}

TEST_CASE("api: a weight file changed on disk after load does not change the loaded model", "[api]") {
    namespace fs = std::filesystem;
    const fs::path copy = fs::temp_directory_path() / "vtloc-test-changed-model.safetensors";
    fs::copy_file(test::tiny_model(), copy, fs::copy_options::overwrite_existing);
    api::Context ctx(test::validated());
    api::Model model(ctx, copy.string());
    api::Object obj = model.encode_object(test::source_path("examples/mug.glb"),
                                          test::source_path("examples/mug_candidates.csv"));
    const api::TouchResult before = model.localize(obj, example_image(1));
    fs::resize_file(copy, fs::file_size(copy) / 2);  // truncated under the running model
    check_same(model.localize(obj, example_image(1)), before, 0);
    api::LocalizeOptions cpu;
    cpu.backend = api::Backend::Cpu;  // built on first use: from memory, not the file
    check_same(model.localize(obj, example_image(1), cpu), before, 2e-3);
    fs::remove(copy);
    test::require_no_validation(ctx);
}

TEST_CASE("api: inspect_model describes the shipped model", "[api]") {
    api::ModelInfo m = api::inspect_model(test::shipped_model());
    CHECK(m.name == "vtloc-r18-half");
    CHECK(m.head == "ilu");
    CHECK(m.has_gma);
    CHECK(m.use_normals);
    CHECK(m.sample_points == 1024);
    CHECK(m.min_points == 512);
    CHECK(m.parameter_count > 3000000);
    CHECK(m.file_bytes < 8u * 1024 * 1024);  // the repository stays small
    CHECK(m.config_json.find("\"vtloc-r18-half\"") != std::string::npos);
    bool f16 = false;
    for (auto& t : m.tensors) f16 |= t.name == "gma.weight" && t.dtype == "F16";
    CHECK(f16);
}

TEST_CASE("api: heat-map PLY, PNG render and tensor dump", "[api]") {
    api::Context ctx(test::validated());
    api::Model model(ctx, test::tiny_model());
    api::Object obj = model.encode_object(test::source_path("examples/mug.glb"));
    api::TactileImage image = example_image(2);
    api::LocalizeOptions opt;
    opt.keep_tensors = true;
    api::TouchResult r = model.localize(obj, image, opt);

    const std::string ply = test::temp_path("api_heatmap.ply"), png = test::temp_path("api_render.png"),
                      dump = test::temp_path("api_dump.safetensors");
    api::write_heatmap_ply(ply, obj, r.heatmap);
    io::PlyVertices v = io::read_ply_vertices(ply);
    CHECK(v.count == int64_t(obj.cloud().size()));
    CHECK(v.column("contact_prob") >= 0);
    CHECK(v.column("red") >= 0);

    api::RenderOptions ro;
    ro.contact = r.contact;
    ro.tactile = &image;
    api::render_heatmap_png(png, obj, r.heatmap, ro);
    io::RgbImage pic = io::load_tactile_image(png);
    CHECK(pic.width == 1280);
    CHECK(pic.height == 720);

    api::save_tensors(dump, r.tensors, model.info().config_json);
    SafetensorsFile f = SafetensorsFile::load(dump);
    for (const char* name : kSpec8) CHECK(f.find(name) != nullptr);
    CHECK(f.at("gma.chamfer").shape.empty());  // 0-d, as weights_tools.golden writes it
    CHECK(f.at("point.sa1.fps").dtype == DType::I32);
    CHECK(f.at("input.tactile").dtype == DType::U8);
    CHECK(f.metadata().count("vtloc.config"));
    CHECK_THAT(test::api_error([&] { api::write_heatmap_ply(ply, obj, {0.5f}); }), Catch::Contains("1 values"));
    test::require_no_validation(ctx);
}
