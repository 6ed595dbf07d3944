// Render-and-compare at the refined poses (engine/track/pose_shape.h): the object rendered
// under the comparison window at an exact pose, a touch's map scored there in the
// codebook's form, and the tracker adding that score to its refined modes (PoseTerm).
#include <catch2/catch.hpp>

#include <cmath>

#include "base/error.h"
#include "engine/io/mesh.h"
#include "engine/sim/mesh_builder.h"
#include "engine/track/pose_shape.h"
#include "engine/track/tracker.h"
#include "tests/track_poses.h"

using namespace vtloc;
using track::Rigid;

namespace {

// The pose pressing `press` mm into the surface at point p (normal n), spun by `spin`.
Rigid pose_at(const std::array<double, 3>& p, const std::array<double, 3>& n, double spin, double press) {
    const float pn[6] = {float(p[0]), float(p[1]), float(p[2]), float(n[0]), float(n[1]), float(n[2])};
    return test::pose_at(pn, spin, press);
}

// A stud: a head (radius 13, 10 mm thick) with a post (radius 6, 30 mm) on its top face.
track::Surface stud(int64_t hypotheses) {
    const io::TriangleMesh m = sim::mesh::revolve({{0, -10}, {13, -10}, {13, 0}, {6, 0}, {6, 30}, {0, 30}}, 96);
    track::SurfaceOptions so;
    so.target_hypotheses = hypotheses;
    return track::build_surface(io::sample_surface(m, 60000, 5, "stud"), true, so, "stud");
}

// What the gel would measure at `pose`: the rendered window pressed `press` past its shallowest cell.
track::ShapeWindow measured_at(const track::PoseShapeScorer& sc, const Rigid& pose, int R, int C, double win, float press) {
    track::ShapeWindow m;
    m.win_mm = win;
    m.press = press;
    m.measured = HostTensor({R, C});
    const std::vector<float> w = sc.render(pose, R, C, win);
    const float top = *std::min_element(w.begin(), w.end()) + press;
    for (size_t k = 0; k < w.size(); ++k) m.measured.data[k] = std::max(0.0f, top - w[k]);
    return m;
}

}  // namespace

TEST_CASE("render-and-compare at a pose: a flat face renders flat, the post's edge where it is", "[track]") {
    const track::Surface s = stud(20000);
    const track::PoseShapeScorer sc(s);
    // Under the head's underside (z = -10, normal -z), 0.8 mm pressed, the 5 x 7 window of 3 mm
    // cells (15 x 21 mm) spans x in [-10.5, 10.5] about x = 0: every cell on the face, depth
    // -0.8 (the points lie 0.8 mm before the pose's origin along its axis).
    const Rigid under = pose_at({0, 0, -10}, {0, 0, -1}, 0, 0.8);
    for (float v : sc.render(under, 5, 7, 3.0)) CHECK(std::abs(v + 0.8f) < 1e-4f);
    // On the top face at r = 9.5 (normal +z): the window reaches the post (r < 6). Its side
    // faces the sensor edge-on (n . z = 0, within the facing limit) and rises toward it, so
    // cells along its wall are shallower than the face; its top is 30 mm away (beyond the
    // cap), so cells over its inside see nothing, like cells beyond the head's rim (r > 13).
    // Cells over the annulus stay at -0.8.
    const Rigid top = pose_at({9.5, 0, 0}, {0, 0, 1}, 0, 0.8);
    const std::vector<float> w = sc.render(top, 7, 7, 3.0);
    REQUIRE(w.size() == 49);
    int wall = 0, inside = 0, face = 0, off = 0, cells[4] = {};
    for (int r = 0; r < 7; ++r)
        for (int c = 0; c < 7; ++c) {
            const double u = (c - 3) * 3.0, v = (r - 3) * 3.0;
            std::array<double, 3> p{};  // the cell centre
            for (int k = 0; k < 3; ++k) p[size_t(k)] = top.t[size_t(k)] + u * top.R[size_t(3 * k)] + v * top.R[size_t(3 * k + 1)];
            const double rad = std::hypot(p[0], p[1]), d = w[size_t(r * 7 + c)];
            if (rad > 5.4 && rad < 6.6) wall += d < -1.5, ++cells[0];
            else if (rad < 5.0) inside += d == 8.0, ++cells[1];
            else if (rad > 6.8 && rad < 12.2) face += std::abs(d + 0.8) < 1e-4, ++cells[2];
            else if (rad > 13.8) off += d == 8.0, ++cells[3];
        }
    INFO("wall " << wall << "/" << cells[0] << ", inside " << inside << "/" << cells[1] << ", face " << face << "/" << cells[2]
                 << ", off the rim " << off << "/" << cells[3]);
    CHECK(cells[0] >= 1);
    CHECK(wall == cells[0]);
    CHECK(inside == cells[1]);
    CHECK(face == cells[2]);
    CHECK(off == cells[3]);
    CHECK(cells[2] >= 10);
    CHECK_THROWS_WITH(sc.render(top, 0, 7, 3.0), Catch::Contains("0 x 7"));
}

TEST_CASE("render-and-compare at a pose: a touch's own pose scores 0, a pose beside it less", "[track]") {
    const track::Surface s = stud(20000);
    const track::PoseShapeScorer sc(s);
    // Near the head's rim from below: the window sees the rim, so a shifted pose sees it elsewhere.
    const Rigid truth = pose_at({7, 2, -10}, {0, 0, -1}, 0.3, 0.8);
    const track::ShapeWindow m = measured_at(sc, truth, 5, 7, 3.0, 0.8f);
    CHECK(std::abs(sc.score(truth, m, 1.0, true)) < 1e-9);
    Rigid beside = truth;
    beside.t[0] -= 3;  // 3 mm toward the axis: the rim leaves part of the window
    const double there = sc.score(beside, m, 1.0, true);
    CHECK(there < -0.05);
    CHECK(sc.score(beside, m, 4.0, true) == Approx(4 * there).epsilon(1e-12));  // the weight scales it
    CHECK(sc.score(beside, m, 0.0, true) == 0);
    track::ShapeWindow none = m;  // no press: no evidence
    std::fill(none.measured.data.begin(), none.measured.data.end(), 0.0f);
    none.press = 0;
    CHECK(sc.score(beside, none, 1.0, true) == 0);
    // A floor bounds a touch's score: log(e^s + e^f) - log(1 + e^f), 0 at the touch's own pose,
    // never below f - log(1 + e^f), between the bare score and 0 elsewhere, and in the bare
    // score's order (a worse match scores lower).
    CHECK(std::abs(sc.score(truth, m, 1.0, true, -5.0)) < 1e-9);
    const double far = sc.score(beside, m, 1e6, true), floored = sc.score(beside, m, 1e6, true, -5.0);
    CHECK(far < -1000);
    CHECK(floored == Approx(-5.0 - std::log1p(std::exp(-5.0))).epsilon(1e-12));
    const double mild = sc.score(beside, m, 1.0, true, -5.0);
    CHECK(mild == Approx(std::log(std::exp(there) + std::exp(-5.0)) - std::log1p(std::exp(-5.0))).epsilon(1e-12));
    CHECK(mild > there);
    CHECK(mild < 0);
    CHECK(sc.score(beside, m, 4.0, true, -5.0) < mild);
    // shape_window: a frame's map averaged onto the window's cells, its press the percentile.
    std::vector<float> depth(size_t(30 * 40), 0.5f);
    const track::ShapeWindow sw = track::shape_window(depth, 30, 40, 0.5, track::ScoreOptions{});
    CHECK(sw.measured.shape == Shape{5, 7});
    CHECK(sw.press == 0.5f);
    CHECK(sw.win_mm == Approx(3.0));
    CHECK_THROWS_WITH(track::shape_window(depth, 30, 41, 0.5, {}), Catch::Contains("1200 values for 30 x 41"));
    // A cloud too sparse to splat is refused as the codebook refuses it (gaps would read as no surface).
    const io::TriangleMesh mesh = sim::mesh::revolve({{0, -10}, {13, -10}, {13, 0}, {6, 0}, {6, 30}, {0, 30}}, 96);
    track::SurfaceOptions so;
    so.target_hypotheses = 2000;
    const track::Surface sparse = track::build_surface(io::sample_surface(mesh, 300, 5, "sparse"), false, so, "sparse");
    CHECK_THROWS_WITH(track::PoseShapeScorer(sparse), Catch::Contains("needs a dense cloud") && Catch::Contains("300 points"));
}

TEST_CASE("the tracker climbs its refined modes on the touches' pose terms: render-and-compare finds the radius on a flat face", "[track]") {
    // Three touches under a stud's head: the geometry fits anywhere on the flat underside
    // (and, free space off, on the top face's annulus turned over). The measured maps,
    // rendered at the true poses, show the head's rim where it is.
    const track::Surface s = stud(20000);
    track::FilterOptions o;
    o.free_space_mm = 0;
    const track::Tracker tr(nullptr, s, o);
    const track::PoseShapeScorer sc(s);
    const std::array<double, 3> under[3] = {{9, 1, -10}, {2, 9.5, -10}, {-6, -7, -10}};
    std::vector<Rigid> poses;
    for (int k = 0; k < 3; ++k) poses.push_back(pose_at(under[k], {0, 0, -1}, 0.4 + k, 0.8));
    const std::vector<Rigid> motions{track::compose(track::inverse(poses[0]), poses[1]),
                                     track::compose(track::inverse(poses[1]), poses[2])};
    std::vector<track::PoseTerm> terms;
    for (const Rigid& p : poses) {
        auto m = std::make_shared<track::ShapeWindow>(measured_at(sc, p, 5, 7, 3.0, 0.8f));
        terms.push_back([&sc, m](const Rigid& x) { return sc.score(x, *m, 64.0, true); });
    }
    track::Tracker a(nullptr, s, o), b(nullptr, s, o);
    const track::Estimate without = a.evaluate_window(motions), with = b.evaluate_window(motions, {}, terms);
    // The stud is a solid of revolution: a pose is right up to a turn about its axis, so the
    // contact's height and radius are what a pose gets right, and the belief's mass on the
    // underside (z < -9) is what it holds on the right face.
    auto err = [&](const track::Estimate& e) {
        return std::hypot(e.pose_contact[2] - under[2][2], std::hypot(e.pose_contact[0], e.pose_contact[1]) - std::hypot(under[2][0], under[2][1]));
    };
    auto underside = [&](const track::Estimate& e) {
        double m = 0;
        for (int64_t i = 0; i < s.n_samples(); ++i)
            if (s.samples[size_t(9 * i + 2)] < -9) m += e.sample_belief[size_t(i)];
        return m;
    };
    INFO("pose error up to a turn without " << err(without) << " mm (fit " << without.fit << "), with " << err(with) << " mm (fit "
                                             << with.fit << ", pose terms " << with.pose_terms << "); mass on the underside "
                                             << underside(without) << " -> " << underside(with));
    CHECK(without.pose_terms == 0);
    // Three touches on the flat underside leave the radius free to the geometry (the climb
    // stops where the grid's pose lay: 2.4 mm off here); the rim in the windows fixes it.
    CHECK(err(without) > 1);
    CHECK(err(with) < 0.5);
    CHECK(with.pose_terms > -1);  // the truth's own maps fit it (up to a turn)
    CHECK(underside(with) > underside(without) + 0.05);
    // The online form carries the pose terms of its window.
    track::Tracker on(nullptr, s, o);
    for (size_t k = 0; k < 3; ++k) on.add_touch(k ? std::optional<Rigid>(motions[k - 1]) : std::nullopt, {}, terms[k]);
    CHECK(on.estimate().contact == with.contact);
    CHECK_THROWS_WITH(b.evaluate_window(motions, {}, {terms[0]}), Catch::Contains("1 pose terms for 3 touches"));
    track::FilterOptions bad = o;
    bad.shape_climb_rounds = -1;
    CHECK_THROWS_WITH(track::Tracker(nullptr, s, bad), Catch::Contains("shape_climb_rounds must be 0..8"));
    bad = o, bad.shape_climb_modes = 1000;
    CHECK_THROWS_WITH(track::Tracker(nullptr, s, bad), Catch::Contains("1000"));
}

TEST_CASE("with odometry noise an earlier touch's pose term is taken where it is best within the noise's widths", "[track]") {
    // Terms peaked (quadratic, curvature a) at each touch's true place, shifted along the gel
    // for the earlier touches as noisy motions would leave them. Shifts along the gel's x and y
    // are what the alignment may undo, each paying its Gaussian prior (sigma = sqrt(steps) x
    // odometry_mm): the best of -a e^2 - e'^2 / (2 sigma^2) over e' is -e^2 a b / (a + b),
    // b = 1 / (2 sigma^2); the offset along the axis stays. The shape climb is off so the
    // estimate's pose is the geometry's and the value can be computed from it.
    const track::Surface s = stud(20000);
    track::FilterOptions o;
    o.free_space_mm = 0;
    o.shape_climb_rounds = 0;
    o.odometry_mm = 0.4;
    o.shape_slack_rounds = 8;
    const std::array<double, 3> under[3] = {{9, 1, -10}, {2, 9.5, -10}, {-6, -7, -10}};
    std::vector<Rigid> poses;
    for (int k = 0; k < 3; ++k) poses.push_back(pose_at(under[k], {0, 0, -1}, 0.4 + k, 0.8));
    const std::vector<Rigid> motions{track::compose(track::inverse(poses[0]), poses[1]),
                                     track::compose(track::inverse(poses[1]), poses[2])};
    const double a = 2.0, shift[3][2] = {{0.9, -0.5}, {0.0, 0.6}, {0, 0}};
    std::vector<track::PoseTerm> terms;
    std::vector<std::array<double, 3>> peak(3);
    for (size_t k = 0; k < 3; ++k) {
        const Rigid& p = poses[k];
        for (int i = 0; i < 3; ++i) peak[k][size_t(i)] = p.t[size_t(i)] + p.R[size_t(3 * i)] * shift[k][0] + p.R[size_t(3 * i + 1)] * shift[k][1];
        terms.push_back([a, c = peak[k]](const Rigid& x) {
            return -a * ((x.t[0] - c[0]) * (x.t[0] - c[0]) + (x.t[1] - c[1]) * (x.t[1] - c[1]) + (x.t[2] - c[2]) * (x.t[2] - c[2]));
        });
    }
    track::FilterOptions rigid_o = o;
    rigid_o.shape_slack_rounds = 0;
    track::Tracker with(nullptr, s, o), rigid(nullptr, s, rigid_o);
    const track::Estimate e = with.evaluate_window(motions, {}, terms), r = rigid.evaluate_window(motions, {}, terms);
    REQUIRE(e.window_poses.size() == 3);
    auto expected = [&](const track::Estimate& est, bool aligned) {
        double v = 0;
        for (size_t k = 0; k < 3; ++k) {
            const Rigid& x = k < 2 ? est.window_poses[k] : est.pose;
            double along[3];  // the offset to the peak in x's own axes
            for (int j = 0; j < 3; ++j) {
                along[j] = 0;
                for (int i = 0; i < 3; ++i) along[j] += x.R[size_t(3 * i + j)] * (peak[k][size_t(i)] - x.t[size_t(i)]);
            }
            const double in_plane = along[0] * along[0] + along[1] * along[1];
            const double sigma2 = double(2 - k) * o.odometry_mm * o.odometry_mm, b = k < 2 ? 1 / (2 * sigma2) : 0;
            v -= a * along[2] * along[2] + (aligned && k < 2 ? in_plane * a * b / (a + b) : a * in_plane);
        }
        return v;
    };
    INFO("pose terms aligned " << e.pose_terms << " (expected " << expected(e, true) << "), rigid " << r.pose_terms << " (expected "
                               << expected(r, false) << ")");
    // The expected values split the offset along the pose's axes, which are orthonormal only to
    // float precision (the refinement starts from the grid's single-precision frames): 1e-6.
    CHECK(r.pose_terms == Approx(expected(r, false)).epsilon(1e-6));
    // The pattern search ends at steps of sigma / 128: its optimum within (sigma / 256)^2 (a + b) a coordinate.
    CHECK(e.pose_terms == Approx(expected(e, true)).margin(1e-3));
    CHECK(e.pose_terms > r.pose_terms + 0.1);
    // No noise, no slack: the terms are read where the motions carry the pose.
    track::FilterOptions exact = o;
    exact.odometry_mm = 0;
    const track::Estimate x = track::Tracker(nullptr, s, exact).evaluate_window(motions, {}, terms);
    CHECK(x.pose_terms == Approx(expected(x, false)).epsilon(1e-6));
    track::FilterOptions bad = o;
    bad.shape_slack_rounds = 9;
    CHECK_THROWS_WITH(track::Tracker(nullptr, s, bad), Catch::Contains("shape_slack_rounds must be 0..8, got 9"));
}
