// api::Tracker from a mesh file: a file wound inward (face normals into the object, e.g.
// an OFF export) is turned outward before the filter samples it, so the true pose is not
// vetoed on every touch; io::orient_outward by the signed volume.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "engine/io/mesh.h"
#include "engine/io/mesh_formats.h"
#include "tests/harness.h"
#include "vtloc/vtloc.h"

using namespace vtloc;

namespace {

io::TriangleMesh rewound(io::TriangleMesh m) {
    for (size_t t = 0; t < m.triangle_count(); ++t) std::swap(m.triangles[3 * t + 1], m.triangles[3 * t + 2]);
    return m;
}

}  // namespace

TEST_CASE("io: orient_outward re-winds a mesh wound inward and leaves an outward one alone", "[io]") {
    const io::TriangleMesh potato = io::load_mesh(std::string(VTLOC_SOURCE_DIR) + "/examples/potato_tour.ply");
    const double v = io::signed_volume(potato);
    REQUIRE(v > 0);
    io::TriangleMesh out = potato, in = rewound(potato);
    CHECK(io::signed_volume(in) == Approx(-v).epsilon(1e-9));
    CHECK_FALSE(io::orient_outward(out));
    CHECK(out.triangles == potato.triangles);
    CHECK(io::orient_outward(in));
    CHECK(in.triangles == potato.triangles);
}

TEST_CASE("tracker: a mesh file wound inward gives the estimate of the outward one", "[api][tracker]") {
    const std::string path = std::string(VTLOC_SOURCE_DIR) + "/examples/potato_tour.ply";
    const std::string inward = test::temp_path("potato-inward.ply");
    io::save_mesh_ply(inward, rewound(io::load_mesh(path)));
    api::Context ctx;
    api::TrackerOptions o;
    o.hypotheses = 20000;
    api::Tracker a(ctx, path, o), b(ctx, inward, o);
    // Two motions over the potato's side: enough geometry to move the belief off uniform.
    const api::Motion m1{{1, 0, 0, 0, 1, 0, 0, 0, 1}, {6, 0, 0}}, m2{{0.866, 0, 0.5, 0, 1, 0, -0.5, 0, 0.866}, {0, 8, 1}};
    const api::TrackerEstimate ea = a.evaluate_window({m1, m2}), eb = b.evaluate_window({m1, m2});
    CHECK(eb.sample_belief == ea.sample_belief);
    CHECK(eb.contact == ea.contact);
    CHECK(eb.heatmap == ea.heatmap);
    CHECK(ctx.take_validation_messages().empty());
}

TEST_CASE("tracker: profile times each GPU step per node and changes no output", "[api][tracker]") {
    const std::string path = std::string(VTLOC_SOURCE_DIR) + "/examples/potato_tour.ply";
    api::Context ctx;
    api::TrackerOptions o;
    o.hypotheses = 5000;
    o.window = 2;  // the third touch's step has the prior's field too
    api::TrackerOptions p = o;
    p.profile = true;
    api::Tracker plain(ctx, path, o), timed(ctx, path, p);
    const api::Tracker timed_too = plain.with_options(p);
    CHECK(timed_too.options().profile);
    CHECK(timed.step_nodes().empty());  // no step yet
    const api::Motion m1{{1, 0, 0, 0, 1, 0, 0, 0, 1}, {6, 0, 0}}, m2{{0.866, 0, 0.5, 0, 1, 0, -0.5, 0, 0.866}, {0, 8, 1}};
    const std::vector<std::optional<api::Motion>> tour{std::nullopt, m1, m2};
    for (const auto& m : tour) {
        plain.add_touch(m);
        timed.add_touch(m);
        CHECK(plain.step_nodes().empty());
        const auto nodes = timed.step_nodes();
        std::vector<std::string> names;
        for (const auto& [name, ms] : nodes) {
            names.push_back(name);
            CHECK(ms >= 0);
            CHECK(std::isfinite(ms));
        }
        // Every step scores the hypotheses and normalises the belief; the node names are the graph's.
        CHECK(std::count(names.begin(), names.end(), "track.evidence") == 1);
        CHECK(std::count(names.begin(), names.end(), "track.belief") == 1);
        const api::TrackerEstimate a = plain.estimate(), b = timed.estimate();
        CHECK(b.sample_belief == a.sample_belief);
        CHECK(b.contact == a.contact);
        CHECK(b.pose.R == a.pose.R);
        CHECK(b.pose.t == a.pose.t);
    }
    CHECK_FALSE(timed.evaluate_window({m1}).sample_belief.empty());
    CHECK_FALSE(timed.step_nodes().empty());  // a window's evaluation is a step too
    CHECK(ctx.take_validation_messages().empty());
}

TEST_CASE("tracker: with_options is a tracker made with those options, its surface not built again", "[api][tracker]") {
    const std::string path = std::string(VTLOC_SOURCE_DIR) + "/examples/potato_tour.ply";
    api::Context ctx;
    api::TrackerOptions o;
    o.hypotheses = 5000;
    api::TrackerOptions other = o;  // filter options only: odometry, window, widths, the rescue
    other.odometry_mm = 0.5, other.odometry_deg = 0.5, other.window = 2, other.sigma_d_mm = 1.3, other.rescue_fit = 0;
    api::Tracker a(ctx, path, o);
    a.add_touch(std::nullopt);  // a's touches are its own: the new tracker starts with none
    const api::Motion m1{{1, 0, 0, 0, 1, 0, 0, 0, 1}, {6, 0, 0}}, m2{{0.866, 0, 0.5, 0, 1, 0, -0.5, 0, 0.866}, {0, 8, 1}};
    // b (made by with_options) against a tracker made from the file with b's options.
    auto same = [&](api::Tracker& b, api::Tracker& made, const api::TrackerOptions& opt) {
        CHECK(b.touches() == 0);
        CHECK(b.options().odometry_mm == opt.odometry_mm);
        CHECK(b.options().window == opt.window);
        CHECK(b.sample_points() == made.sample_points());
        for (api::Tracker* t : {&b, &made}) {
            t->add_touch(std::nullopt);
            t->add_touch(m1);
            t->add_touch(m2);  // past the window of 2: the prior takes the first
        }
        const api::TrackerEstimate eb = b.estimate(), em = made.estimate();
        CHECK(eb.sample_belief == em.sample_belief);
        CHECK(eb.contact == em.contact);
        CHECK(eb.pose.R == em.pose.R);
        CHECK(eb.pose.t == em.pose.t);
        CHECK(eb.fit == em.fit);
        CHECK(eb.heatmap == em.heatmap);
        CHECK(b.evaluate_window({m1, m2}).sample_belief == made.evaluate_window({m1, m2}).sample_belief);
    };
    // The new tracker shares what the surface alone shapes (the surface, its tables, the
    // registration's k-d tree) where `from` has it and makes what it lacks: both ways must
    // match a tracker made from the file.
    auto same_as_made = [&](const api::Tracker& from, const api::TrackerOptions& opt) {
        api::Tracker b = from.with_options(opt), made(ctx, path, opt);
        same(b, made, opt);
    };
    same_as_made(a, other);
    CHECK(a.options().window == o.window);
    // From a tracker with neither (no registration, no field slack) to one that needs both,
    // and back.
    api::TrackerOptions bare = o, both = other;
    bare.register_rounds = 0;
    both.field_slack = true;
    const api::Tracker a_bare(ctx, path, bare);
    auto a_both = std::make_unique<const api::Tracker>(ctx, path, both);
    same_as_made(a_bare, both);
    same_as_made(*a_both, bare);
    CHECK(a.touches() == 1);
    {
        // What it shares outlives the tracker it came from (ASan in CI would catch a read of
        // freed tables).
        api::Tracker b = a_both->with_options(other);
        a_both.reset();
        api::Tracker made(ctx, path, other);
        same(b, made, other);
    }
    // What shapes the surface stays; a bad option is refused as the constructor refuses it.
    auto refused = [&](api::TrackerOptions x, const char* name) {
        INFO(name);
        CHECK_THROWS_WITH(a.with_options(x), Catch::Contains(name));
    };
    api::TrackerOptions x = o;
    x.n_spin = 18;
    refused(x, "n_spin");
    x = o, x.hypotheses = 6000;
    refused(x, "hypotheses");
    x = o, x.candidates = {{0, 0, 0}};
    refused(x, "candidates");
    x = o, x.object_units = 10;
    refused(x, "object_units");
    x = o, x.window = 0;
    refused(x, "window");
    x = o, x.render_cell_mm = 20;
    refused(x, "render_cell_mm");
    x = o, x.odometry_mm = INFINITY;  // would turn field_slack's widths to 0 and the geometry's infinite
    refused(x, "odometry noise finite");
    x = o, x.odometry_deg = -1;
    refused(x, "odometry noise finite and >= 0");
    x = o, x.odometry_mm = 1e7;  // finite, but its squares reach float's limits in the widths
    refused(x, "at most 1e6");
    CHECK(ctx.take_validation_messages().empty());
}
