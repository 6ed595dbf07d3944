// api::GelShapeReader: the GPU pipeline equals engine/sensor's CPU one on real presses,
// larger frames of the same aspect are resampled, other sizes are errors.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "engine/api/api_internal.h"
#include "engine/sensor/gel_shape.h"
#include "engine/sensor/lighting.h"
#include "engine/track/codebook.h"
#include "tests/api_test_util.h"
#include "tests/harness.h"
#include "vtloc/vtloc.h"

using namespace vtloc;

namespace {

// Real press i of the calibration as the RGB frame a PNG gives (the file stores BGR).
api::TactileImage press(const sensor::Calibration& c, int i) {
    api::TactileImage im;
    im.height = c.height, im.width = c.width;
    const size_t n = size_t(c.height) * size_t(c.width);
    for (size_t p = 0; p < n; ++p)
        for (int k = 2; k >= 0; --k) im.rgb.push_back(c.press_imgs[size_t(i) * n * 3 + 3 * p + size_t(k)]);
    return im;
}

// A gentle cap tilted a little along x.
api::GelShape tilted_cap() { return test::gel_cap(7.5, 10.0, 0.01); }

}  // namespace

TEST_CASE("gel shape reader: the GPU pipeline equals the CPU one on real presses", "[api][sensor]") {
    const sensor::Calibration c = sensor::load_calibration(sensor::default_calibration_path());
    const sensor::GradientLut lut = sensor::build_gradient_lut(c);
    api::Context ctx(api::ContextOptions{"", api::Validation::On});
    // The real frames' reader (50 sweeps from zeros) and the rendered frames' (a coarse start:
    // its mask threshold takes in most of a real press's frame, a wide mask).
    const api::GelShapeOptions rendered = api::GelShapeOptions::rendered_frames();
    const sensor::ShapeOptions cpu_rendered = sensor::rendered_frame_options();
    CHECK(rendered.mask_threshold == cpu_rendered.mask_threshold);
    CHECK((rendered.levels == cpu_rendered.sor_levels && rendered.coarse_iterations == cpu_rendered.sor_coarse_iterations &&
           rendered.iterations == cpu_rendered.sor_iterations));
    api::GelShapeOptions one_thread;
    one_thread.threads = 1;  // its tables built on one host thread: the same bits (test_sensor_gel_shape)
    for (bool wide : {false, true}) {
        api::GelShapeReader reader(ctx, wide ? rendered : one_thread);
        CHECK((reader.width() == 160 && reader.height() == 120));
        for (int i : {0, 17, 40}) {
            INFO("press " << i << (wide ? ", the rendered frames' reader" : ""));
            const size_t n = size_t(c.height) * size_t(c.width);
            const std::vector<uint8_t> bgr(c.press_imgs.begin() + long(size_t(i) * n * 3), c.press_imgs.begin() + long(size_t(i + 1) * n * 3));
            // The reader matches the frame's lighting to the empty frame first (engine/sensor/lighting.h).
            const sensor::GelShape cpu =
                sensor::gel_shape(c, lut, sensor::match_lighting(bgr, c.press_f0), c.press_f0, wide ? cpu_rendered : sensor::ShapeOptions{});
            const api::GelShape gpu = reader.read(press(c, i));
            REQUIRE(gpu.depth_mm.size() == n);
            size_t differ = 0, contact = 0;
            double worst = 0;
            for (size_t p = 0; p < n; ++p) {
                differ += gpu.mask[p] != cpu.mask[p], contact += cpu.mask[p];
                worst = std::max(worst, double(std::abs(gpu.depth_mm[p] - cpu.depth_mm[p])));
            }
            CHECK(differ == 0);  // the gradients agree to fp32 rounding: no pixel crosses the threshold
            CHECK(contact > (wide ? n / 4 : 200));
            // The solve's sweeps (coarse grids and the full one) accumulate the gradients' rounding:
            // within a micrometre.
            CHECK(worst < 1e-3);
        }
    }
    CHECK(ctx.take_validation_messages().empty());
}

TEST_CASE("gel shape reader: a larger frame of the same aspect is resampled, others refused", "[api][sensor]") {
    const sensor::Calibration c = sensor::load_calibration(sensor::default_calibration_path());
    api::Context ctx;
    api::GelShapeReader reader(ctx);
    const api::TactileImage small = press(c, 8);
    api::TactileImage big;  // every pixel doubled: area resampling gives the frame back exactly
    big.height = 2 * small.height, big.width = 2 * small.width;
    for (int r = 0; r < big.height; ++r)
        for (int col = 0; col < big.width; ++col)
            for (int k = 0; k < 3; ++k) big.rgb.push_back(small.rgb[(size_t(r / 2) * size_t(small.width) + size_t(col / 2)) * 3 + size_t(k)]);
    CHECK(reader.read(big).depth_mm == reader.read(small).depth_mm);
    api::TactileImage square;
    square.height = square.width = 120;
    square.rgb.assign(120 * 120 * 3, 100);
    CHECK_THROWS_WITH(reader.read(square), Catch::Contains("frame: 120x120 for the calibration's 160x120: another aspect"));
    api::TactileImage tiny;
    tiny.height = 60, tiny.width = 80;
    tiny.rgb.assign(60 * 80 * 3, 100);
    CHECK_THROWS_WITH(reader.read(tiny), Catch::Contains("smaller than the calibration"));
    CHECK_THROWS_WITH(reader.read(small, &square), Catch::Contains("empty frame: 120x120"));
    CHECK_THROWS_WITH(reader.read(square, nullptr, "sq.png"), Catch::StartsWith("sq.png: 120x120 for the calibration's"));
    api::GelShapeOptions bad;
    bad.calibration = "/no/such/calib.safetensors";
    CHECK_THROWS_WITH(api::GelShapeReader(ctx, bad), Catch::Contains("/no/such/calib.safetensors"));
    for (int threads : {-1, 257}) {
        api::GelShapeOptions o;
        o.threads = threads;
        CHECK_THROWS_WITH(api::GelShapeReader(ctx, o), Catch::Contains("threads must be 0..256"));
    }
}

TEST_CASE("gel shape reader: black, over-exposed and flat frames are refused, naming which frame", "[api][sensor][errors]") {
    // Until 2026-12-06 an all-black or all-white frame read as a 140 mm^2 contact 7 mm deep.
    const sensor::Calibration c = sensor::load_calibration(sensor::default_calibration_path());
    api::Context ctx;
    api::GelShapeReader reader(ctx);
    auto flat = [&](uint8_t v) {
        api::TactileImage im;
        im.height = c.height, im.width = c.width;
        im.rgb.assign(size_t(c.height) * size_t(c.width) * 3, v);
        return im;
    };
    const api::TactileImage real = press(c, 8);
    CHECK_THROWS_WITH(reader.read(flat(0)), Catch::Contains("frame: the frame is black (its brightest value is 0 of 255)"));
    CHECK_THROWS_WITH(reader.read(flat(255)), Catch::Contains("frame: 100 % of the frame is white"));
    CHECK_THROWS_WITH(reader.read(flat(128)), Catch::Contains("frame: the frame is one flat colour (values 128..128)"));
    const api::TactileImage dark = flat(3);
    CHECK_THROWS_WITH(reader.read(real, &dark), Catch::StartsWith("empty frame: the frame is black"));
    // Named frames (a caller's file paths) head their errors instead.
    CHECK_THROWS_WITH(reader.read(flat(0), nullptr, "touches/3.png"), Catch::StartsWith("touches/3.png: the frame is black"));
    CHECK_THROWS_WITH(reader.read(real, &dark, "touches/3.png", "bg.png"), Catch::StartsWith("bg.png: the frame is black"));
    // Half a real press painted white: over half the pixels clipped is refused, under half read.
    api::TactileImage half = real;
    for (size_t p = 0; p < half.rgb.size() / 3 / 2 + 1; ++p) half.rgb[3 * p] = half.rgb[3 * p + 1] = half.rgb[3 * p + 2] = 255;
    CHECK_THROWS_WITH(reader.read(half), Catch::Contains("50 % of the frame is white"));
    for (size_t p = half.rgb.size() / 3 / 2 - 200; p < half.rgb.size() / 3 / 2 + 1; ++p)
        for (int k = 0; k < 3; ++k) half.rgb[3 * p + size_t(k)] = real.rgb[3 * p + size_t(k)];
    CHECK(reader.read(half).depth_mm.size() == size_t(c.height) * size_t(c.width));
    // A dim frame still reads (its brightest value 32 and more).
    api::TactileImage dim = real;
    for (uint8_t& v : dim.rgb) v = uint8_t(v / 7);
    CHECK(reader.read(dim).depth_mm.size() == size_t(c.height) * size_t(c.width));
    // check_frame refuses what read refuses, with the same words, and passes what it reads.
    api::TactileImage square;
    square.height = square.width = 120;
    square.rgb.assign(120 * 120 * 3, 100);
    for (const auto& fe : std::vector<std::pair<api::TactileImage, const api::TactileImage*>>{
             {flat(0), nullptr}, {flat(255), nullptr}, {flat(128), nullptr}, {real, &dark}, {square, nullptr}, {real, &square}}) {
        const api::TactileImage& f = fe.first;  // not a structured binding: clang 14 cannot capture one
        const api::TactileImage* e = fe.second;
        const std::string read = test::api_error([&] { reader.read(f, e, "touches/3.png", "bg.png"); });
        CHECK(!read.empty());
        CHECK(test::api_error([&] { reader.check_frame(f, e, "touches/3.png", "bg.png"); }) == read);
    }
    CHECK_NOTHROW(reader.check_frame(real));
    CHECK_NOTHROW(reader.check_frame(dim, &real));
}

TEST_CASE("tracker: precomputed touch terms give the windowed estimate of the shapes themselves", "[api][tracker]") {
    // Two gentle caps pressed into the gel, one motion between them, on the potato; the terms are
    // computed once (touch_term) and reused, as vtloc eval does across windows.
    api::Context ctx;
    api::TrackerOptions o;
    o.hypotheses = 20000;
    api::Tracker t(ctx, std::string(VTLOC_SOURCE_DIR) + "/examples/potato_tour.ply", o);
    const api::GelShape a = test::gel_cap(7.5, 10.0, 0), b = test::gel_cap(6.0, 11.0, 0);
    const api::Motion m{{1, 0, 0, 0, 1, 0, 0, 0, 1}, {3, 0, 0}};
    const api::TrackerEstimate direct = t.evaluate_window({m}, {}, nullptr, {&a, &b});
    const std::vector<std::vector<float>> terms{t.touch_term(nullptr, nullptr, &a), t.touch_term(nullptr, nullptr, &b)};
    // The shapes go along for render-and-compare at the refined poses (render_refined_weight).
    const api::TrackerEstimate reused = t.evaluate_window_terms({m}, terms, {&a, &b});
    CHECK(terms[0] == t.shape_term(a));
    CHECK(reused.sample_belief == direct.sample_belief);
    CHECK(reused.contact == direct.contact);
    CHECK(direct.pose_terms < 0);  // the shapes' score at the estimate's poses (0 is a perfect match)
    CHECK(t.evaluate_window({m}).pose_terms == 0);
    CHECK(t.touch_term(nullptr, nullptr, nullptr).empty());  // no network, no shape: no term
    CHECK(t.evaluate_window_terms({m}, {{}, {}}).sample_belief == t.evaluate_window({m}).sample_belief);
    CHECK_THROWS_WITH(t.evaluate_window_terms({m}, {terms[0]}), Catch::Contains("1 touch terms for 2 touches"));
    CHECK_THROWS_WITH(t.evaluate_window_terms({m}, terms, {&a}), Catch::Contains("1 gel shapes for 2 touches"));
    {  // At weight 0 the shapes only enter through the grid's term; the default scores them at the refined poses.
        api::TrackerOptions off = o;
        off.render_refined_weight = 0;
        api::Tracker t0 = t.with_options(off);
        CHECK(t0.evaluate_window_terms({m}, terms, {&a, &b}).sample_belief == t0.evaluate_window_terms({m}, terms).sample_belief);
        CHECK(t.evaluate_window_terms({m}, terms, {&a, &b}).sample_belief != t.evaluate_window_terms({m}, terms).sample_belief);
        off.render_refined_weight = -1;
        CHECK_THROWS_WITH(t.with_options(off), Catch::Contains("render_refined_weight"));
        // The floor reaches the refined poses' scores (their bounds: tests/test_pose_shape.cpp):
        // without one (-inf) this window's estimate scores its shapes otherwise.
        api::TrackerOptions bare = o;
        bare.render_refined_floor = -INFINITY;
        CHECK(t.with_options(bare).evaluate_window_terms({m}, terms, {&a, &b}).pose_terms !=
              t.evaluate_window_terms({m}, terms, {&a, &b}).pose_terms);
        bare.render_refined_floor = NAN;
        CHECK_THROWS_WITH(t.with_options(bare), Catch::Contains("render_refined_floor"));
        bare.render_refined_floor = INFINITY;
        CHECK_THROWS_WITH(t.with_options(bare), Catch::Contains("render_refined_floor"));
        // With odometry noise the earlier shape is also scored where it matches within the noise
        // (render_slack_rounds); without noise the option changes nothing.
        api::TrackerOptions noisy = o, rigid = o;
        noisy.odometry_mm = rigid.odometry_mm = 0.5;
        rigid.render_slack_rounds = 0;
        const api::TrackerEstimate en = t.with_options(noisy).evaluate_window_terms({m}, terms, {&a, &b});
        const api::TrackerEstimate er = t.with_options(rigid).evaluate_window_terms({m}, terms, {&a, &b});
        CHECK(en.sample_belief != er.sample_belief);
        // The grid reads the earlier term widened within the noise (field_slack); without, at the nearest
        // hypothesis. These shapes' terms span only ~0.04 nats, far less than a neighbour ~4 mm away costs
        // at 0.5 mm of noise (35 nats), so here the terms are sharpened 1000 times and the noise is 2 mm.
        std::vector<std::vector<float>> sharp = terms;
        for (auto& f : sharp)
            for (float& v : f) v *= 1000;
        api::TrackerOptions widened = noisy;
        widened.odometry_mm = 2, widened.field_slack = true;
        api::TrackerOptions unwidened = widened;
        unwidened.field_slack = false;
        CHECK(t.with_options(unwidened).evaluate_window_terms({m}, sharp).sample_belief !=
              t.with_options(widened).evaluate_window_terms({m}, sharp).sample_belief);
        rigid.odometry_mm = 0;
        CHECK(t.with_options(rigid).evaluate_window_terms({m}, terms, {&a, &b}).sample_belief == reused.sample_belief);
        rigid.render_slack_rounds = 9;
        CHECK_THROWS_WITH(t.with_options(rigid), Catch::Contains("render_slack_rounds must be 0..8"));
    }
    CHECK_THROWS_WITH(t.evaluate_window_terms({m}, {terms[0], std::vector<float>(7)}), Catch::Contains("7"));
    // Online with the same terms: add_touch_term is add_touch with the shape, and reset starts over.
    t.add_touch(std::nullopt, nullptr, nullptr, &a);
    t.add_touch(m, nullptr, nullptr, &b);
    const std::vector<float> online = t.belief();
    t.reset();
    CHECK(t.touches() == 0);
    t.add_touch_term(std::nullopt, terms[0], &a);
    t.add_touch_term(m, terms[1], &b);
    CHECK(t.touches() == 2);
    CHECK(t.belief() == online);
    CHECK(t.estimate().sample_belief == direct.sample_belief);  // two touches: the online form is the windowed one
    CHECK_THROWS_WITH(t.add_touch_term(m, std::vector<float>(7)), Catch::Contains("7"));
    CHECK(ctx.take_validation_messages().empty());
}

TEST_CASE("tracker: the shape term's press percentile, quadratic fit and cell are options, checked by name", "[api][tracker]") {
    // A tilted cap with a noise spike at its deepest cell: the maximum follows the spike, a
    // percentile of the pressed cells does not; the quadratic fit also drops a bowl.
    api::Context ctx;
    api::TrackerOptions o;
    o.hypotheses = 5000;
    const std::string potato = std::string(VTLOC_SOURCE_DIR) + "/examples/potato_tour.ply";
    api::GelShape g = tilted_cap();
    for (int r = 58; r < 62; ++r)
        for (int c = 78; c < 82; ++c) g.depth_mm[size_t(r * g.width + c)] += 1.5f;  // a 0.5 mm spike, 1.5 mm high
    std::vector<float> terms[4];
    for (int k = 0; k < 4; ++k) {
        api::TrackerOptions ok = o;
        ok.render_press_percentile = k == 0 ? 100 : 95;
        ok.render_quadratic = k >= 2;
        ok.render_cell_mm = k == 3 ? 3.0 : 1.0;
        api::Tracker t(ctx, potato, ok);
        terms[k] = t.shape_term(g);
        REQUIRE(terms[k].size() >= 2500);
    }
    CHECK(terms[0] != terms[1]);
    CHECK(terms[1] != terms[2]);
    CHECK(terms[2] != terms[3]);
    for (const auto& f : terms)
        for (float v : f) REQUIRE((std::isfinite(v) && v <= 0.0f));
    for (double bad : {0.0, -5.0, 101.0}) {
        api::TrackerOptions ob = o;
        ob.render_press_percentile = bad;
        CHECK_THROWS_WITH(api::Tracker(ctx, potato, ob), Catch::Contains("render_press_percentile"));
    }
    for (double bad : {0.05, 11.0, std::nan("")}) {
        api::TrackerOptions ob = o;
        ob.render_cell_mm = bad;
        CHECK_THROWS_WITH(api::Tracker(ctx, potato, ob), Catch::Contains("render_cell_mm"));
    }
    api::TrackerOptions neg = o;
    neg.render_weight = -1;
    CHECK_THROWS_WITH(api::Tracker(ctx, potato, neg), Catch::Contains("render_weight"));
    // The public defaults are the scorer's (the header cannot include the engine's, so both are written).
    const track::ScoreOptions so;
    const api::TrackerOptions to;
    CHECK(to.render_weight == so.weight);
    CHECK(to.render_quadratic == so.quadratic);
    CHECK(to.render_press_percentile == so.press_percentile);
    CHECK(to.render_cell_mm == so.cell_mm);
    CHECK(ctx.take_validation_messages().empty());
}

TEST_CASE("tracker: with_options' trackers share the codebook, each scoring with its own options", "[api][tracker]") {
    // Rendering an object's codebook is seconds (the potato at 120,000 hypotheses: 1.5 s) and
    // its maps are most of a render-and-compare tracker's device memory: a tracker made by
    // with_options reuses both, unless it names another cache file.
    const std::string potato = std::string(VTLOC_SOURCE_DIR) + "/examples/potato_tour.ply";
    api::Context ctx;
    rt::Context& rtc = api::ContextAccess::rt(ctx);
    api::TrackerOptions o;
    o.hypotheses = 5000;
    api::GelShape g = tilted_cap();
    o.register_rounds = 0, o.deep_modes = 0;  // no search tree: host_bytes moves by the pose scorer's bins alone
    api::Tracker a(ctx, potato, o);
    const api::Tracker early = a.with_options(o);  // made before any gel shape
    const uint64_t a_host = a.host_bytes(), early_host = early.host_bytes();
    const std::vector<float> ta = a.shape_term(g);
    api::TrackerOptions other = o;  // the comparison's own knobs differ, and a filter option
    other.render_weight = 0.5, other.render_quadratic = false, other.render_press_percentile = 90, other.render_cell_mm = 2;
    other.odometry_mm = 0.5;
    const api::Tracker b = a.with_options(other);
    const uint64_t before = rtc.memory_in_use();
    const std::vector<float> tb = const_cast<api::Tracker&>(b).shape_term(g);
    const uint64_t grew = rtc.memory_in_use() - before;
    // The maps alone: a map of at least 25 x 25 cells (the window's 12.5 mm reach at 1 mm) a
    // sample; the device holds them as quads, 4.4 times that.
    const uint64_t maps = 4 * 25 * 25 * uint64_t(a.sample_points().size() / 3);
    INFO("the second tracker's first gel shape added " << grew << " bytes; the maps are at least " << maps);
    CHECK(grew < maps / 2);
    api::Tracker made(ctx, potato, other), like_a(ctx, potato, o);
    CHECK(tb == made.shape_term(g));  // as a tracker rendering its own, bit for bit
    CHECK(ta == like_a.shape_term(g));
    CHECK(tb != ta);
    CHECK(a.shape_term(g) == ta);  // a's own options still a's
    // Render-and-compare at the refined poses bins the dense points once, for every tracker of
    // the object, even one made before the first gel shape.
    const api::Motion m{{1, 0, 0, 0, 1, 0, 0, 0, 1}, {3, 0, 0}};
    CHECK(a.evaluate_window({m}, {}, nullptr, {&g, &g}).pose_terms < 0);
    const uint64_t bins = a.host_bytes() - a_host;
    CHECK(bins >= 24 * uint64_t(a.sample_points().size() / 3));  // a point and its normal, at least a sample's worth
    CHECK(early.host_bytes() - early_host == bins);
    // Another cache file is read or written by the tracker that names it.
    const std::string cache = test::temp_path("with-options-codebook.safetensors");
    std::filesystem::remove(cache);
    api::TrackerOptions cached = o;
    cached.codebook_cache = cache;
    api::Tracker c = a.with_options(cached);
    CHECK(c.shape_term(g) == ta);
    CHECK(std::filesystem::exists(cache));
    CHECK(ctx.take_validation_messages().empty());
}
