// The evaluation metrics (engine/sim/metrics.h, docs/eval.md) on hand-made
// cases, and the subset rule on analytic shapes.
#include <catch2/catch.hpp>
#include <cmath>

#include "engine/io/mesh.h"
#include "engine/sensor/calibration.h"
#include "engine/sim/metrics.h"
#include "engine/sim/point_filtering.h"
#include "engine/sim/shapes.h"
#include "engine/sim/touch_renderer.h"
#include "engine/sim/uniformity.h"

using namespace vtloc;
using sim::Point3;

namespace {

HostTensor tensor(const std::vector<Point3>& pts) {
    HostTensor t({int64_t(pts.size()), 3});
    for (size_t i = 0; i < pts.size(); ++i)
        for (size_t k = 0; k < 3; ++k) t.data[i * 3 + k] = float(pts[i][k]);
    return t;
}

// Six points at +-8 on the axes, in +- pairs: centre exactly 0, scale 8, D 16,
// so the normalised frame is exact and ties stay ties.
const std::vector<Point3> kOcta{{8, 0, 0}, {-8, 0, 0}, {0, 8, 0}, {0, -8, 0}, {0, 0, 8}, {0, 0, -8}};

sim::MetricObject octa(const std::vector<Point3>& candidates) {
    return sim::MetricObject::make(tensor(kOcta), tensor(candidates));
}

}  // namespace

TEST_CASE("eval metrics: the object frame and D", "[eval]") {
    const sim::MetricObject o = octa({{8, 0, 0}});
    CHECK(o.centre == Point3{0, 0, 0});
    CHECK(o.scale == 8.0);
    CHECK(o.diameter == 16.0);
    CHECK(o.candidates_n[0] == Point3{1, 0, 0});
    CHECK_THROWS(sim::MetricObject::make(tensor({{1, 1, 1}, {1, 1, 1}}), tensor({{1, 1, 1}})));
}

TEST_CASE("eval metrics: a perfect predictor", "[eval]") {
    const sim::MetricObject o = octa(kOcta);  // every point a candidate
    for (size_t j = 0; j < kOcta.size(); ++j) {
        // K = 1: the heat-map is then exactly the ground-truth map. (With K > 1
        // the runner-up candidates light up too, so even a perfect prediction
        // has MPE > 0: MPE measures the heat-map, not the point.)
        const sim::TouchMetrics m = sim::touch_metrics(o, kOcta[j], kOcta[j], {}, {}, 1);
        CHECK(m.error_mm == 0.0);
        CHECK(m.nd == 0.0);
        CHECK(m.rank == 1);
        CHECK(m.mpe == 0.0);
        const sim::TouchMetrics m5 = sim::touch_metrics(o, kOcta[j], kOcta[j], {}, {}, 5);
        CHECK(m5.rank == 1);
        CHECK(m5.mpe > 0.0);
    }
    std::vector<std::vector<sim::TouchScore>> scores(1);
    for (const Point3& p : kOcta) scores[0].push_back(sim::score(sim::touch_metrics(o, p, p, {}, {}, 1)));
    const sim::RowMetrics r = sim::aggregate(scores);
    CHECK(r.objects == 1);
    CHECK(r.touches == 6);
    CHECK(r.mm == 0.0);
    CHECK(r.nd == 0.0);
    CHECK(r.top1 == 100.0);
    CHECK(r.top5 == 100.0);
    CHECK(r.mpe == 0.0);
}

TEST_CASE("eval metrics: a predictor at a known offset", "[eval]") {
    const sim::MetricObject o = octa(kOcta);
    // 3-4-5: 5 mm off on an object of D = 16 mm -> ND 31.25 %.
    const Point3 gt = kOcta[0], pred{8 - 3, 4, 0};
    const sim::TouchMetrics m = sim::touch_metrics(o, pred, gt);
    CHECK(m.error_mm == Approx(5.0).epsilon(1e-12));
    CHECK(m.nd == Approx(31.25).epsilon(1e-12));
    CHECK(m.rank == 1);  // (5, 4, 0) is still nearest to (8, 0, 0)
    // Moved towards (0, 8, 0): that candidate wins, the truth is second.
    const sim::TouchMetrics m2 = sim::touch_metrics(o, {3, 6, 0}, gt);
    CHECK(m2.rank == 2);
    CHECK(m2.error_mm == Approx(std::sqrt(25.0 + 36.0)));
}

TEST_CASE("eval metrics: ranks break ties to the lower index", "[eval]") {
    // Candidates +x (0) and -x (1); a prediction at the centre is equally far from both.
    const sim::MetricObject o = octa({{8, 0, 0}, {-8, 0, 0}, {0, 8, 0}});
    CHECK(sim::order_by_distance(o.candidates_n, {0, 0, 0}) == std::vector<int>{0, 1, 2});
    CHECK(sim::order_by_distance(o.candidates_n, {-0.5, 0, 0}) == std::vector<int>{1, 2, 0});
    CHECK(sim::touch_metrics(o, {0, 0, 0}, {8, 0, 0}).rank == 1);
    CHECK(sim::touch_metrics(o, {0, 0, 0}, {-8, 0, 0}).rank == 2);
    // The ground-truth candidate itself: a contact halfway between 0 and 1 is candidate 0's.
    CHECK(sim::nearest(o.candidates_n, {0, 0, 0.25}) == 0);
    CHECK(sim::touch_metrics(o, {-8, 0, 0}, {0, 0, 0}).rank == 3);
    // A method's own ranking overrides the distance order.
    CHECK(sim::touch_metrics(o, {8, 0, 0}, {0, 8, 0}, {2, 0, 1}).rank == 1);
}

TEST_CASE("eval metrics: per object first, then over objects", "[eval]") {
    const sim::MetricObject o = octa(kOcta);
    // Object A: one touch, ~6 mm off and second-ranked; object B: three perfect touches.
    std::vector<std::vector<sim::TouchScore>> scores(2);
    const sim::TouchMetrics a = sim::touch_metrics(o, {4, 4.5, 0}, kOcta[0]);
    scores[0].push_back(sim::score(a));
    REQUIRE(a.rank == 2);
    for (int i = 0; i < 3; ++i) scores[1].push_back(sim::score(sim::touch_metrics(o, kOcta[2], kOcta[2], {}, {}, 1)));
    const sim::RowMetrics r = sim::aggregate(scores);
    CHECK(r.objects == 2);
    CHECK(r.touches == 4);
    CHECK(r.mm == Approx(a.error_mm / 2));     // not a.error_mm / 4 (the mean over touches)
    CHECK(r.nd == Approx(a.nd / 2));
    CHECK(r.top1 == Approx(50.0));             // not 75 %
    CHECK(r.top5 == Approx(100.0));
    CHECK(r.mpe == Approx(a.mpe / 2));
    // An object without touches does not count.
    scores.push_back({});
    CHECK(sim::aggregate(scores).objects == 2);
    CHECK(sim::aggregate({}).objects == 0);
}

TEST_CASE("eval metrics: heat-maps follow SPEC section 3", "[eval]") {
    const std::vector<Point3> pts{{0, 0, 0}, {1, 0, 0}, {3, 0, 0}};
    // Rank 1 at 0, rank 2 at 3: s = (1, e^-1, 1/2) -> min-max over the three points.
    const std::vector<float> h = sim::topk_heatmap(pts, {{0, 0, 0}, {3, 0, 0}});
    const double e1 = std::exp(-1.0);
    CHECK(h[0] == Approx(1.0));
    CHECK(h[1] == Approx(0.0));
    CHECK(h[2] == Approx((0.5 - e1) / (1 - e1)));
    const std::vector<float> g = sim::gt_heatmap(pts, {0, 0, 0});
    CHECK(g[0] == Approx(1.0));
    CHECK(g[2] == Approx(0.0));
    CHECK(g[1] == Approx((e1 - std::exp(-3.0)) / (1 - std::exp(-3.0))));
    CHECK(sim::mean_abs_diff(h, g) == Approx((std::abs(h[1] - g[1]) + std::abs(h[2] - g[2])) / 3).epsilon(1e-6));
    // Flat: zeros.
    CHECK(sim::topk_heatmap({{1, 1, 1}}, {{0, 0, 0}}) == std::vector<float>{0.0f});
}

TEST_CASE("eval metrics: the analytic Chance row", "[eval]") {
    // Candidates on the x axis at 0, 8 and -8 (object units); the truth is candidate 0.
    const sim::MetricObject o = octa({{0, 0, 0}, {8, 0, 0}, {-8, 0, 0}});
    const auto heats = sim::chance_heatmaps(o, 2);
    const sim::ChanceMetrics c = sim::chance_metrics(o, {0, 0, 0}, heats, 2);
    CHECK(c.error_mm == Approx((0.0 + 8 + 8) / 3));
    CHECK(c.nd == Approx(100.0 * (16.0 / 3) / 16));
    CHECK(c.top1 == Approx(1.0 / 3));  // only a draw of the truth itself ranks it first
    CHECK(c.top5 == Approx(1.0));      // three candidates: always within the top 5
    // MPE: the mean over the three draws of their own heat-map's MPE.
    double mpe = 0;
    for (size_t j = 0; j < 3; ++j) mpe += sim::touch_metrics(o, o.candidates[j], {0, 0, 0}, {}, {}, 2).mpe / 3;
    CHECK(c.mpe == Approx(mpe).epsilon(1e-12));
    // The truth at +8: a draw of 0 ranks candidate 1 second (tie with 2 broken to the lower index).
    const sim::ChanceMetrics c1 = sim::chance_metrics(o, {8, 0, 0}, heats, 2);
    CHECK(c1.error_mm == Approx((8.0 + 0 + 16) / 3));
    CHECK(c1.top1 == Approx(1.0 / 3));
    const sim::TouchScore s = sim::score(c1);
    CHECK(s.top1 == Approx(1.0 / 3));
}

TEST_CASE("eval metrics: subset labels on analytic shapes", "[eval]") {
    const HostTensor sphere = io::sample_surface(sim::make_shape("sphere"), 1024, 7, "sphere");
    const sim::Uniformity us = sim::measure_uniformity(sphere);
    CHECK(us.uniform);
    CHECK(us.share_below >= 0.7);
    const HostTensor comb = io::sample_surface(sim::make_shape("comb_fine"), 1024, 7, "comb_fine");
    const sim::Uniformity uc = sim::measure_uniformity(comb);
    CHECK_FALSE(uc.uniform);
    CHECK(uc.share_below < 0.7);
}

TEST_CASE("point filtering: a candidate's own render ranks it first", "[eval]") {
    const io::TriangleMesh mesh = sim::make_shape("comb_fine");
    const sim::Calibration calib = sim::load_calibration(sim::default_calibration_path());
    // Candidates: surface samples where the simulator can place the sensor.
    const HostTensor cloud = io::sample_surface(mesh, 64, 11, "comb_fine");
    sim::TouchRenderer renderer(calib, mesh);
    sim::Appearance plain;
    plain.noise_sigma = 0;
    sim::TouchParams press;
    press.press_mm = sim::PointFilterOptions{}.press_mm;
    std::vector<Point3> cands, normals;
    std::vector<sim::Touch> touches;
    for (int64_t i = 0; i < cloud.shape[0] && cands.size() < 4; ++i) {
        const float* r = &cloud.data[size_t(i) * 6];
        const Point3 p{r[0], r[1], r[2]}, n{r[3], r[4], r[5]};
        sim::Touch t = renderer.render(p, n, press, plain, 0);
        if (!t.ok || t.contact_pixels < 50) continue;
        cands.push_back(p);
        normals.push_back(n);
        touches.push_back(std::move(t));
    }
    REQUIRE(cands.size() == 4);
    const sim::PointFilter pf(calib, mesh, {}, cands, normals, std::nullopt);
    CHECK(pf.unrenderable() == 0);
    for (size_t i = 0; i < cands.size(); ++i) {
        // Spin 0 is one of the filter's spins, so the observed frame is one of its renders: d = 0.
        const sim::Frame8 observed{calib.height, calib.width, touches[i].image};
        const std::vector<double> d = pf.distances(observed);
        CHECK(d[i] == Approx(0.0).margin(1e-6));
        const std::vector<int> ranking = pf.ranking(observed);
        CHECK(d[size_t(ranking[0])] == Approx(0.0).margin(1e-6));
        for (double x : d) CHECK(x >= -1e-6);  // 1 - NCC, up to float rounding
    }
    // The empty sensor is flat after background subtraction: distance 1 to everything.
    const sim::Frame8 empty{calib.height, calib.width, renderer.background_frame(plain)};
    for (double x : pf.distances(empty)) CHECK(x == Approx(1.0));
}
