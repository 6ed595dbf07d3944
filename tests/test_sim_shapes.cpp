// Procedural training objects: valid closed meshes at their design size, the
// simple solids uniform and the toothed set non-uniform by SPEC section 5.
#include <catch2/catch.hpp>
#include <random>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <vector>
#include <set>
#include <utility>

#include "engine/io/mesh.h"
#include "engine/sim/everyday_shapes.h"
#include "engine/sim/mesh_builder.h"
#include "engine/sim/shapes.h"
#include "engine/sim/symmetry.h"
#include "engine/sim/uniformity.h"
#include "tests/io_test_util.h"

using namespace vtloc;

namespace {

const std::set<std::string> kUniformSolids = {"box", "cylinder", "sphere", "cone", "torus", "capsule"};
// Designed to be non-uniform (each measured at <= 0.65 over seeds 0-4).
const std::set<std::string> kToothed = {"comb_fine",  "comb_coarse", "hair_pick",        "saw_blade",
                                        "gear_cassette", "pin_heatsink", "rasp",         "file",
                                        "corrugated_plate", "brush",  "studded_plate",   "bolt",
                                        "knurled_cylinder", "ridged_cylinder"};

}  // namespace

TEST_CASE("shapes: every name builds a closed outward mesh at its design size", "[sim]") {
    const auto names = sim::shape_names();
    REQUIRE(names.size() >= kUniformSolids.size() + kToothed.size());
    for (const auto& n : kUniformSolids) CHECK(std::count(names.begin(), names.end(), n) == 1);
    for (const auto& n : kToothed) CHECK(std::count(names.begin(), names.end(), n) == 1);
    for (const std::string& name : names) {
        INFO("shape " << name);
        io::TriangleMesh m = sim::make_shape(name);
        REQUIRE(m.triangle_count() > 0);
        CHECK(m.triangle_count() <= 100000);
        CHECK(m.normals.empty());  // face normals keep the teeth sharp
        // Counted, then asserted once: an assertion per coordinate and index made millions.
        REQUIRE(std::count_if(m.positions.begin(), m.positions.end(), [](float x) { return !std::isfinite(x); }) == 0);
        REQUIRE(std::count_if(m.triangles.begin(), m.triangles.end(), [&](uint32_t v) { return v >= m.vertex_count(); }) == 0);
        const double extent = io::bounds(m).largest_side();
        CHECK(extent == Approx(sim::shape_scale_mm(name)).epsilon(0.01));
        CHECK(sim::shape_scale_mm(name) >= 50);
        CHECK(sim::shape_scale_mm(name) <= 250);

        // No degenerate triangle, and closed with consistent winding: every
        // directed edge appears once and its reverse once.
        std::vector<uint64_t> edges;  // directed edges as (from << 32 | to), sorted below
        size_t degenerate = 0;
        for (size_t t = 0; t < m.triangle_count(); ++t) {
            const uint32_t* v = &m.triangles[3 * t];
            double e[2][3], c[3];
            for (int a = 0; a < 3; ++a) {
                e[0][a] = double(m.positions[3 * v[1] + a]) - m.positions[3 * v[0] + a];
                e[1][a] = double(m.positions[3 * v[2] + a]) - m.positions[3 * v[0] + a];
            }
            c[0] = e[0][1] * e[1][2] - e[0][2] * e[1][1];
            c[1] = e[0][2] * e[1][0] - e[0][0] * e[1][2];
            c[2] = e[0][0] * e[1][1] - e[0][1] * e[1][0];
            if (!(0.5 * std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) > 1e-6)) ++degenerate;  // mm^2
            for (int k = 0; k < 3; ++k) edges.push_back(uint64_t(v[k]) << 32 | v[(k + 1) % 3]);
        }
        CHECK(degenerate == 0);
        std::sort(edges.begin(), edges.end());
        size_t unpaired = 0;  // distinct edges seen more than once or without their reverse
        for (size_t i = 0; i < edges.size();) {
            size_t j = i;
            while (j < edges.size() && edges[j] == edges[i]) ++j;
            const uint64_t reverse = edges[i] << 32 | edges[i] >> 32;
            if (j - i != 1 || !std::binary_search(edges.begin(), edges.end(), reverse)) ++unpaired;
            i = j;
        }
        CHECK(unpaired == 0);
        CHECK(sim::mesh::signed_volume(m) > 0);
    }
}

TEST_CASE("shapes: simple solids are uniform, at least 10 toothed ones are not", "[sim]") {
    std::string table = "shape              tris    share(dn<30)  label\n";
    int non_uniform = 0;
    for (const std::string& name : sim::shape_names()) {
        io::TriangleMesh m = sim::make_shape(name);
        sim::Uniformity u = sim::measure_uniformity(io::sample_surface(m, 1024, io::kDefaultSampleSeed, name));
        char line[128];
        std::snprintf(line, sizeof line, "%-18s %6zu  %.3f         %s\n", name.c_str(), m.triangle_count(),
                      u.share_below, u.uniform ? "uniform" : "non-uniform");
        table += line;
        INFO("shape " << name << " share " << u.share_below);
        if (kUniformSolids.count(name)) CHECK(u.uniform);
        if (kToothed.count(name) && !u.uniform) ++non_uniform;
    }
    WARN(table);
    CHECK(non_uniform >= 10);
}

TEST_CASE("shapes: an unknown name lists the known ones", "[sim]") {
    test::require_error([] { sim::make_shape("teapot"); }, {"teapot", "box", "comb_fine", "rasp"});
    test::require_error([] { sim::shape_scale_mm("teapot"); }, {"teapot", "sphere"});
}

TEST_CASE("mesh builder: polygon triangulation covers a non-convex outline", "[sim]") {
    // A U shape, given clockwise: area 3 * 3 - 1 * 2 = 7.
    std::vector<sim::mesh::P2> u = {{0, 0}, {0, 3}, {1, 3}, {1, 1}, {2, 1}, {2, 3}, {3, 3}, {3, 0}};
    std::vector<uint32_t> tri = sim::mesh::triangulate_polygon(u);
    REQUIRE(tri.size() == 3 * (u.size() - 2));
    double area = 0;
    for (size_t t = 0; t < tri.size(); t += 3) {
        auto a = u[tri[t]], b = u[tri[t + 1]], c = u[tri[t + 2]];
        double s = 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
        CHECK(s > 0);  // counter-clockwise whatever the input direction
        area += s;
    }
    CHECK(area == Approx(7.0));
    io::TriangleMesh prism = sim::mesh::extrude(u, 0, 2);
    CHECK(sim::mesh::signed_volume(prism) == Approx(14.0));
}

TEST_CASE("declared symmetry groups hold: each shape maps onto itself within 0.2 mm", "[sim][symmetry]") {
    int declared = 0;
    for (const std::string& name : sim::shape_names()) {
        const sim::Symmetry s = sim::shape_symmetry(name);
        if (s.none()) continue;
        ++declared;
        INFO(name);
        const io::TriangleMesh mesh = sim::make_shape(name);
        // The everyday objects' groups on fewer points: 11 more meshes of 20-80k
        // triangles, most of them turned at 24 angles, would add seconds.
        const bool everyday = std::any_of(sim::everyday_shapes().begin(), sim::everyday_shapes().end(),
                                          [&](const sim::EverydayShape& e) { return name == e.name; });
        CHECK(sim::symmetry_residual_mm(s, mesh, everyday ? 150 : 400) <= 0.2);
        // ... and the check can fail: a quarter turn is no symmetry of the box, a tilted axis none of the cone.
    }
    CHECK(declared >= 8);
    sim::Symmetry quarter;
    quarter.order = 4;
    CHECK(sim::symmetry_residual_mm(quarter, sim::make_shape("box"), 400) > 5);
    sim::Symmetry tilted;
    tilted.order = 0;
    tilted.axis = {0, 0.2, 1};
    CHECK(sim::symmetry_residual_mm(tilted, sim::make_shape("cone"), 400) > 1);
    sim::Symmetry round;  // every rotation: the sphere's group, not the box's
    round.all = true;
    CHECK(sim::shape_symmetry("sphere").all);
    CHECK(sim::symmetry_residual_mm(round, sim::make_shape("box"), 400) > 5);
}

namespace {

sim::Symmetry turn_about(const sim::Vec3d& axis, int order, const sim::Vec3d& point) {
    sim::Symmetry t;
    t.order = order;
    t.axis = axis;
    t.point = point;
    return t;
}

// Whether the group holds t's first turn: one of its elements moves two generic points alike
// (within twice the 0.2 mm: a mesh's axis may sit that far off its bounding box's centre).
bool group_holds(const sim::Symmetry& s, const sim::Symmetry& t) {
    const sim::Mat3d turn = t.rotations()[1];
    for (const sim::Mat3d& g : s.rotations()) {
        double d = 0;
        for (const sim::Vec3d& q : {sim::Vec3d{3.1, -7.7, 11.3}, sim::Vec3d{-19.4, 5.9, -2.6}}) {
            const sim::Vec3d u = s.apply(g, q), v = t.apply(turn, q);
            d = std::max({d, std::abs(u[0] - v[0]), std::abs(u[1] - v[1]), std::abs(u[2] - v[2])});
        }
        if (d < 0.4) return true;
    }
    return false;
}

// Every shape turned by each of `turns` (axis, order) through its bounding box's centre; where
// that maps it onto itself (the declared groups' 0.2 mm), its group must hold the turn.
// Returns how many turns mapped a shape onto itself.
int check_undeclared_turns(const std::vector<std::pair<sim::Vec3d, int>>& turns, int samples) {
    int found = 0;
    for (const std::string& name : sim::shape_names()) {
        const sim::Symmetry s = sim::shape_symmetry(name);
        if (s.all) continue;
        const io::TriangleMesh mesh = sim::make_shape(name);
        const sim::Vec3d centre = io::bounds(mesh).centre();
        for (const auto& [axis, order] : turns) {
            const sim::Symmetry t = turn_about(axis, order, centre);
            if (sim::symmetry_residual_mm(t, mesh, samples) > 0.2) continue;
            ++found;
            INFO(name << ": a turn of 1/" << order << " about (" << axis[0] << ", " << axis[1] << ", " << axis[2] << ") maps it onto itself");
            CHECK(group_holds(s, t));
        }
    }
    return found;
}

const sim::Vec3d kX{1, 0, 0}, kY{0, 1, 0}, kZ{0, 0, 1};

}  // namespace

TEST_CASE("no shape has a half turn about its frame's axes that its group lacks", "[sim][symmetry]") {
    // A symmetry left undeclared makes ND "up to symmetry" count its copies as misses: the
    // mirror-built combs, plates and gears had theirs missing until 2026-12-05.
    CHECK(check_undeclared_turns({{kX, 2}, {kY, 2}, {kZ, 2}}, 400) >= 20);  // the box's three, the cylinders', ...
    // ... and the check can fail: the box's group lacks a quarter turn, the cone's a half turn about x.
    CHECK_FALSE(group_holds(sim::shape_symmetry("box"), turn_about(kZ, 4, {0, 0, 0})));
    CHECK_FALSE(group_holds(sim::shape_symmetry("cone"), turn_about(kX, 2, {0, 0, 0})));
    CHECK(group_holds(sim::shape_symmetry("cone"), turn_about(kZ, 7, {0, 0, 0})));
}

TEST_CASE("no shape has a third, quarter, fifth, sixth or eighth turn about its frame's axes, or a half turn "
          "about their diagonals, that its group lacks", "[long][sim][symmetry]") {
    // Beyond the half turns above (2026-12-06: none found on any shape; 2.5 s, so in the long suite).
    std::vector<std::pair<sim::Vec3d, int>> turns;
    for (const sim::Vec3d& a : {kX, kY, kZ})
        for (int order : {3, 4, 5, 6, 8}) turns.push_back({a, order});
    const double r = std::sqrt(0.5);
    for (const sim::Vec3d& d : {sim::Vec3d{r, r, 0}, sim::Vec3d{r, -r, 0}, sim::Vec3d{r, 0, r}, sim::Vec3d{r, 0, -r},
                                sim::Vec3d{0, r, r}, sim::Vec3d{0, r, -r}})
        turns.push_back({d, 2});
    CHECK(check_undeclared_turns(turns, 200) >= 40);  // the round shapes' every turn about their axis
}

TEST_CASE("distance up to symmetry, and the symmetry's JSON", "[sim][symmetry]") {
    sim::Symmetry ring;  // every angle about z, with the flip about x
    ring.order = 0;
    ring.flip = sim::Vec3d{1, 0, 0};
    CHECK(sim::distance_up_to_symmetry(ring, {10, 0, 3}, {0, -10, 3}) == Approx(0).margin(1e-9));
    CHECK(sim::distance_up_to_symmetry(ring, {10, 0, 3}, {0, 10, -3}) == Approx(0).margin(1e-9));  // flipped
    CHECK(sim::distance_up_to_symmetry(ring, {10, 0, 3}, {0, 12, 3}) == Approx(2));
    sim::Symmetry two;  // a half turn about z
    two.order = 2;
    CHECK(sim::distance_up_to_symmetry(two, {5, 1, 0}, {-5, -1, 0}) == Approx(0).margin(1e-9));
    CHECK(sim::distance_up_to_symmetry(two, {5, 1, 0}, {-5, 1, 0}) == Approx(2));
    CHECK(sim::distance_up_to_symmetry(sim::Symmetry{}, {1, 2, 3}, {1, 2, 5}) == Approx(2));
    const sim::Symmetry back = sim::symmetry_from_json(sim::symmetry_json(ring), "x");
    CHECK(back.order == 0);
    CHECK(back.flip.has_value());
    CHECK(sim::symmetry_json(sim::Symmetry{}).is_null());
    CHECK_THROWS_WITH(sim::symmetry_from_json(nlohmann::json{{"point", {0, 0, 0}}, {"axis", {0, 0, 1}}, {"order", 2}, {"flip", {0, 0.5, 1}}}, "o.json"),
                      Catch::Contains("o.json: symmetry flip axis must be perpendicular"));
    CHECK_THROWS_WITH(sim::symmetry_from_json(nlohmann::json{{"axis", {0, 0, 1}}}, "o.json"), Catch::Contains("o.json: symmetry must be"));
    // Finite, but its squared length overflows: it must not normalise to a zero axis.
    CHECK_THROWS_WITH(sim::symmetry_from_json(nlohmann::json{{"point", {0, 0, 0}}, {"axis", {1e200, 0, 0}}, {"order", 2}}, "o.json"),
                      Catch::Contains("o.json: symmetry axis is too long to normalise"));
    CHECK_THROWS_WITH(sim::symmetry_from_json(nlohmann::json{{"point", {0, 0, 0}}, {"axis", {0, 0, 1}}, {"order", 2}, {"flip", {0, 1e200, 0}}}, "o.json"),
                      Catch::Contains("o.json: symmetry flip axis is too long to normalise"));
    CHECK_THROWS_WITH(sim::symmetry_from_json(nlohmann::json{{"point", {0, 0, 0}}, {"axis", {0, 0, 0}}, {"order", 2}}, "o.json"),
                      Catch::Contains("o.json: symmetry axis is zero"));
    // Every rotation about a point: only the distances to it count.
    sim::Symmetry round;
    round.all = true;
    round.point = {1, 0, 0};
    CHECK(!round.none());
    CHECK(sim::distance_up_to_symmetry(round, {4, 4, 0}, {1, 0, 5}) == Approx(0).margin(1e-9));
    CHECK(sim::distance_up_to_symmetry(round, {1, 0, 6}, {-4, 0, 0}) == Approx(1));
    const sim::Symmetry rb = sim::symmetry_from_json(sim::symmetry_json(round), "x");
    CHECK(rb.all);
    CHECK(rb.point == round.point);
    CHECK(sim::symmetry_json(round) == nlohmann::json{{"point", {1, 0, 0}}, {"all", true}});
    for (const nlohmann::json& bad : {nlohmann::json{{"point", {0, 0, 0}}, {"all", false}}, nlohmann::json{{"all", true}},
                                      nlohmann::json{{"point", {0, 0, 0}}, {"all", true}, {"order", 2}}})
        CHECK_THROWS_WITH(sim::symmetry_from_json(bad, "o.json"), Catch::Contains("o.json: a spherical symmetry is"));
}

TEST_CASE("distance up to symmetry: the closed form equals the nearest of every group element", "[sim][symmetry]") {
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(-30, 30);
    for (int order : {1, 2, 3, 7, 63, 80})
        for (int variant = 0; variant < 3; ++variant) {
            sim::Symmetry s;
            s.order = order;
            s.point = {u(rng) / 10, u(rng) / 10, u(rng) / 10};
            s.axis = variant == 0 ? sim::Vec3d{0, 0, 1} : sim::Vec3d{0.3, -0.5, 0.8};
            if (variant == 2) {  // a flip axis perpendicular to the tilted axis
                const sim::Vec3d a = s.axis;
                s.flip = sim::Vec3d{a[1], -a[0], 0};
            }
            if (order == 1 && variant != 2) continue;  // no group
            for (int i = 0; i < 50; ++i) {
                const sim::Vec3d p{u(rng), u(rng), u(rng)}, t{u(rng), u(rng), u(rng)};
                double brute = 1e300;
                for (const sim::Mat3d& R : s.rotations()) {
                    const sim::Vec3d q = s.apply(R, t);
                    brute = std::min(brute, std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2])));
                }
                INFO("order " << order << " variant " << variant);
                CHECK(sim::distance_up_to_symmetry(s, p, t) == Approx(brute).margin(1e-6));
            }
        }
}

