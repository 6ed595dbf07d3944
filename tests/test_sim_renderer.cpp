// The simulated GelSight touch renderer (engine/sim/touch_renderer.h):
// background, contact geometry, ground truth, rejection, open meshes,
// determinism (the calibration loader: test_sim_calibration.cpp).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <numeric>

#include "base/error.h"
#include "engine/safetensors.h"
#include "engine/sensor/calibration.h"
#include "engine/sim/primitives.h"
#include "engine/sim/touch_renderer.h"
#include "tests/harness.h"
#include "tests/sim_fixtures.h"

using namespace vtloc;
using namespace vtloc::sim;

using test::calib;
using test::no_noise;

namespace {

double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 column(const SensorPose& p, int k) { return {p.R[k], p.R[3 + k], p.R[6 + k]}; }

// Appends m (translated by t) to out.
void append(io::TriangleMesh& out, const io::TriangleMesh& m, Vec3 t = {0, 0, 0}) {
    uint32_t base = uint32_t(out.vertex_count());
    for (size_t v = 0; v < m.vertex_count(); ++v)
        for (int k = 0; k < 3; ++k) out.positions.push_back(float(m.positions[v * 3 + k] + t[k]));
    for (uint32_t i : m.triangles) out.triangles.push_back(base + i);
}

// Rectangle [x0, x1] x [y0, y1] at height z, facing +z.
io::TriangleMesh rect_z(double x0, double x1, double y0, double y1, double z) {
    io::TriangleMesh m = make_plane(x1 - x0, y1 - y0);
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        m.positions[v * 3] += float((x0 + x1) / 2);
        m.positions[v * 3 + 1] += float((y0 + y1) / 2);
        m.positions[v * 3 + 2] = float(z);
    }
    m.normals.clear();
    return m;
}

// A wall at x = x0 from z0 to z1, y in [-30, 30].
io::TriangleMesh wall_x(double x0, double z0, double z1) {
    io::TriangleMesh m;
    m.positions = {float(x0), -30, float(z0), float(x0), 30, float(z0), float(x0), 30, float(z1), float(x0), -30, float(z1)};
    m.triangles = {0, 1, 2, 0, 2, 3};
    return m;
}

void flip_winding(io::TriangleMesh& m) {
    for (size_t t = 0; t < m.triangle_count(); ++t) std::swap(m.triangles[t * 3 + 1], m.triangles[t * 3 + 2]);
}

// Equivalent-area radius (pixels) of the pixels with indentation > eps.
double area_radius(const Touch& t, double eps = 0) {
    int n = 0;
    for (float v : t.indentation_mm) n += v > eps;
    return std::sqrt(n / M_PI);
}

}  // namespace

TEST_CASE("sim: a large flat plane pressed gives the background plus noise only", "[sim]") {
    const Calibration& c = calib();
    const size_t n = size_t(c.height) * c.width;
    io::TriangleMesh plane = make_plane(100, 100, 3, 3);
    TouchRenderer r(c, plane);
    TouchParams p;
    p.press_mm = 0.8;
    p.spin_deg = 37;
    const std::vector<uint8_t> bg = r.background_frame(no_noise());

    Touch t = r.render({1, 2, 0}, {0, 0, 1}, p, no_noise(), 7);
    REQUIRE(t.ok);
    CHECK(t.image == bg);
    CHECK(t.contact_pixels == int(n));
    for (float v : t.indentation_mm) REQUIRE(v == Approx(0.8).margin(1e-5));
    // The gel sits press_mm below the plane, the sensor looks down.
    CHECK(t.pose.t[2] == Approx(-0.8).margin(1e-9));
    CHECK(column(t.pose, 2)[2] == Approx(-1).margin(1e-12));

    // With depth_bg in the height (README step 1) the undeformed frame is
    // close to the real empty frame (~29 without it).
    double mad = 0;
    for (size_t i = 0; i < n * 3; ++i) mad += std::abs(int(bg[i]) - int(c.press_f0[i]));
    CHECK(mad / (n * 3) < 6.0);

    // The same plane with flipped winding (a back face) renders the same.
    io::TriangleMesh flipped = plane;
    flip_winding(flipped);
    Touch tf = TouchRenderer(c, flipped).render({1, 2, 0}, {0, 0, 1}, p, no_noise(), 7);
    REQUIRE(tf.ok);
    CHECK(tf.image == bg);

    // Noise: per-pixel differences have std ~ sigma (clipped pixels left out).
    Appearance noisy;
    noisy.noise_sigma = 3;
    Touch tn = r.render({1, 2, 0}, {0, 0, 1}, p, noisy, 11);
    double s = 0, s2 = 0;
    int m = 0;
    for (size_t i = 0; i < n * 3; ++i) {
        if (bg[i] < 15 || bg[i] > 240) continue;
        double d = double(tn.image[i]) - bg[i];
        s += d, s2 += d * d, ++m;
    }
    REQUIRE(m > int(n));
    double mean = s / m, sd = std::sqrt(s2 / m - mean * mean);
    CHECK(std::abs(mean) < 0.1);
    CHECK(sd > 2.85);
    CHECK(sd < 3.2);
}

TEST_CASE("sim: a pressed sphere's contact radius is sqrt(2Rd - d^2)", "[sim]") {
    const Calibration& c = calib();
    const double R = 5, mmpp = c.mm_per_px;
    TouchRenderer r(c, make_icosphere(R, 6));
    for (double d : {0.3, 0.8, 1.5}) {
        TouchParams p;
        p.press_mm = d;
        p.spin_deg = 120;
        Touch t = r.render({0, 0, R}, {0, 0, 1}, p, no_noise(), 0);
        REQUIRE(t.ok);
        const double want = std::sqrt(2 * R * d - d * d) / mmpp;
        // The contact mask is the undeformed intersection of gel plane and sphere.
        CHECK(std::sqrt(t.contact_pixels / M_PI) == Approx(want).margin(1.0));
        // After the drape the indentation spreads beyond the contact...
        CHECK(area_radius(t) > want + 3);
        // ...while it never sinks below the sphere, and in the middle of the
        // contact keeps the sphere's shape. (Near the cut edge the draped gel
        // may stand off the steep sides, as in Hertz contact, whose contact
        // radius is sqrt(R d), smaller than the cut's.)
        const int H = c.height, W = c.width;
        double worst = 0, deepest_gap = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                double rho = std::hypot(x - (W - 1) / 2.0, y - (H - 1) / 2.0) * mmpp;
                if (rho >= R) continue;
                double analytic = d - (R - std::sqrt(R * R - rho * rho));
                double got = t.indentation_mm[size_t(y) * W + x];
                deepest_gap = std::max(deepest_gap, analytic - got);
                if (rho < 0.5 * want * mmpp) worst = std::max(worst, std::abs(got - analytic));
            }
        CHECK(worst < 0.005);
        CHECK(deepest_gap < 1e-3);  // faceting of the icosphere: ~0.0004 mm
        // Far from the contact the gel is flat again.
        CHECK(t.indentation_mm[0] < 0.02f);
    }
}

TEST_CASE("sim: ground truth is the centre ray's hit, with tilt", "[sim]") {
    const Calibration& c = calib();
    TouchParams p;
    p.press_mm = 1.2;
    p.tilt_deg = 3;
    p.tilt_dir_deg = 30;
    p.spin_deg = 200;

    SECTION("plane z = 0, the point given above it") {
        TouchRenderer r(c, make_plane(200, 200));
        const Vec3 q{1, 2, 0.3}, n{0, 0, 1};
        Touch t = r.render(q, n, p, no_noise(), 0);
        REQUIRE(t.ok);
        Vec3 x = column(t.pose, 0), y = column(t.pose, 1), z = column(t.pose, 2);
        // Right-handed orthonormal, axis 8 degrees off -n.
        CHECK(dot(x, x) == Approx(1));
        CHECK(dot(x, y) == Approx(0).margin(1e-12));
        CHECK(x[1] * y[2] - x[2] * y[1] == Approx(z[0]).margin(1e-12));
        CHECK(std::acos(-dot(z, n)) * 180 / M_PI == Approx(3).margin(1e-9));
        // Centre ray q + s z meets z = 0 at s = -q_z / z_z.
        double s = -q[2] / z[2];
        for (int k = 0; k < 3; ++k) CHECK(t.contact[k] == Approx(q[k] + s * z[k]).margin(1e-9));
        CHECK(t.normal[2] == Approx(1));
        // Gel plane: first touch at the expanded window's lowest corner,
        // depth w = (u n.x + v n.y) / -n.z from q, then pressed.
        const int M = int(std::ceil(2.0 / c.mm_per_px - 1e-9));
        double U = (c.width + 2 * M - 1) / 2.0 * c.mm_per_px, V = (c.height + 2 * M - 1) / 2.0 * c.mm_per_px;
        double w0 = (q[2] - U * std::abs(x[2]) - V * std::abs(y[2])) / -z[2];
        for (int k = 0; k < 3; ++k) CHECK(t.pose.t[k] == Approx(q[k] + (w0 + p.press_mm) * z[k]).margin(1e-9));
        // Tilted: one side of the window presses deeper than the other.
        CHECK(t.contact_pixels < c.height * c.width);
        // Tilted 8 degrees, the window's far corner reaches the plane ~1.7 mm
        // before the centre: a 0.6 mm press leaves the centre untouched.
        TouchParams steep = p;
        steep.tilt_deg = 8;
        steep.press_mm = 0.6;
        Touch s8 = r.render(q, n, steep, no_noise(), 0);
        CHECK_FALSE(s8.ok);
        CHECK(std::string(s8.reason) == "gel hits other geometry first");
    }
    SECTION("sphere, the point given off its surface") {
        const double R = 5;
        TouchRenderer r(c, make_icosphere(R, 6));
        const Vec3 q{0.5, 0.3, 5.5};
        Touch t = r.render(q, {0, 0, 1}, p, no_noise(), 0);
        REQUIRE(t.ok);
        Vec3 z = column(t.pose, 2);
        // First root of |q + s z| = R.
        double b = dot(q, z), cc = dot(q, q) - R * R, s = -b - std::sqrt(b * b - cc);
        for (int k = 0; k < 3; ++k) CHECK(t.contact[k] == Approx(q[k] + s * z[k]).margin(2e-3));
        CHECK(std::sqrt(dot(t.contact, t.contact)) == Approx(R).margin(2e-3));
        for (int k = 0; k < 3; ++k) CHECK(t.normal[k] == Approx(t.contact[k] / R).margin(0.02));
        // The sensor centre lies on the same axis.
        Vec3 d{t.pose.t[0] - t.contact[0], t.pose.t[1] - t.contact[1], t.pose.t[2] - t.contact[2]};
        double len = std::sqrt(dot(d, d));
        CHECK(std::abs(dot(d, z)) == Approx(len).margin(1e-9));
    }
}

TEST_CASE("sim: touches the flat sensor cannot make are rejected", "[sim]") {
    const Calibration& c = calib();
    // A slot 2 mm wide and 5 mm deep in a flat top.
    io::TriangleMesh slot;
    append(slot, rect_z(-30, -1, -30, 30, 5));
    append(slot, rect_z(1, 30, -30, 30, 5));
    append(slot, rect_z(-1, 1, -30, 30, 0));
    append(slot, wall_x(-1, 0, 5));
    append(slot, wall_x(1, 0, 5));
    TouchRenderer r(c, slot);
    TouchParams p;
    p.press_mm = 1.5;
    Touch bottom = r.render({0, 0, 0}, {0, 0, 1}, p, no_noise(), 0);
    CHECK_FALSE(bottom.ok);
    CHECK(std::string(bottom.reason) == "gel hits other geometry first");
    CHECK(bottom.image.empty());

    Touch top = r.render({10, 0, 5}, {0, 0, 1}, p, no_noise(), 0);
    CHECK(top.ok);

    Touch miss = r.render({100, 0, 5}, {0, 0, 1}, p, no_noise(), 0);
    CHECK_FALSE(miss.ok);
    CHECK(std::string(miss.reason) == "centre ray misses the mesh");

    Touch bad = r.render({0, 0, 0}, {0, 0, 0}, p, no_noise(), 0);
    CHECK_FALSE(bad.ok);
    p.press_mm = -1;
    CHECK_THROWS_AS(r.render({10, 0, 5}, {0, 0, 1}, p, no_noise(), 0), Error);
}

TEST_CASE("sim: open meshes and back faces leave no holes", "[sim]") {
    const Calibration& c = calib();
    const double R = 5;
    io::TriangleMesh sphere = make_icosphere(R, 5), cap;
    // The upper half only, normals dropped: an open single-sided surface.
    for (size_t t = 0; t < sphere.triangle_count(); ++t) {
        double zc = 0;
        for (int k = 0; k < 3; ++k) zc += sphere.positions[sphere.triangles[t * 3 + k] * 3 + 2];
        if (zc > 0)
            for (int k = 0; k < 3; ++k) cap.triangles.push_back(sphere.triangles[t * 3 + k]);
    }
    cap.positions = sphere.positions;
    io::TriangleMesh flipped = cap;
    flip_winding(flipped);
    TouchParams p;
    p.press_mm = 1.0;
    Touch a = TouchRenderer(c, cap).render({0, 0, R}, {0, 0, 1}, p, no_noise(), 3);
    Touch b = TouchRenderer(c, flipped).render({0, 0, R}, {0, 0, 1}, p, no_noise(), 3);
    REQUIRE(a.ok);
    REQUIRE(b.ok);
    CHECK(a.image == b.image);
    CHECK(a.indentation_mm == b.indentation_mm);
    // Every pixel of the contact disc is pressed.
    const double rc = std::sqrt(2 * R - 1) / c.mm_per_px;
    int holes = 0;
    for (int y = 0; y < c.height; ++y)
        for (int x = 0; x < c.width; ++x)
            if (std::hypot(x - (c.width - 1) / 2.0, y - (c.height - 1) / 2.0) < 0.97 * rc)
                holes += !(a.indentation_mm[size_t(y) * c.width + x] > 0);
    CHECK(holes == 0);

    // A grid of 1-pixel cells whose edges and diagonals run exactly through
    // pixel centres (binary-exact pixel size and coordinates): a pixel on a
    // shared edge must be covered by one of its triangles, else it stays at
    // +inf depth, i.e. unpressed.
    const double px = 0.125;
    io::TriangleMesh grid;
    const int cells = 240;
    for (int j = 0; j <= cells; ++j)
        for (int i = 0; i <= cells; ++i)
            grid.positions.insert(grid.positions.end(), {float((i - cells / 2) * px), float((j - cells / 2) * px), 0.0f});
    for (int j = 0; j < cells; ++j)
        for (int i = 0; i < cells; ++i) {
            uint32_t a = j * (cells + 1) + i, b = a + 1, d = a + cells + 1, e = d + 1;
            grid.triangles.insert(grid.triangles.end(), {a, b, e, a, e, d});
        }
    Touch g = TouchRenderer(c, grid, px).render({px / 2, px / 2, 0}, {0, 0, 1}, p, no_noise(), 0);
    REQUIRE(g.ok);
    CHECK(g.contact_pixels == c.height * c.width);
    for (float v : g.indentation_mm) REQUIRE(v == Approx(1.0));
}

TEST_CASE("sim: noise is deterministic per seed", "[sim]") {
    const Calibration& c = calib();
    io::TriangleMesh sphere = make_icosphere(4, 4);
    TouchParams p;
    Appearance look;  // default noise
    Touch a = TouchRenderer(c, sphere).render({0, 0, 4}, {0, 0, 1}, p, look, 42);
    Touch b = TouchRenderer(c, sphere).render({0, 0, 4}, {0, 0, 1}, p, look, 42);
    Touch d = TouchRenderer(c, sphere).render({0, 0, 4}, {0, 0, 1}, p, look, 43);
    REQUIRE(a.ok);
    CHECK(a.image == b.image);
    CHECK(a.image != d.image);
    CHECK(a.indentation_mm == d.indentation_mm);
    Touch e = TouchRenderer(c, sphere).render({0, 0, 4}, {0, 0, 1}, p, no_noise(), 1);
    Touch f = TouchRenderer(c, sphere).render({0, 0, 4}, {0, 0, 1}, p, no_noise(), 2);
    CHECK(e.image == f.image);
}

TEST_CASE("sim: appearance applies gain, brightness and a user background", "[sim]") {
    const Calibration& c = calib();
    TouchRenderer r(c, make_plane(10, 10));
    std::vector<uint8_t> plain = r.background_frame(no_noise());
    Appearance user = no_noise();
    user.background = c.real_bg;
    for (float& v : user.background) v += 10;
    Appearance bright = no_noise();
    bright.brightness = 10;
    CHECK(r.background_frame(user) == r.background_frame(bright));
    std::vector<uint8_t> ub = r.background_frame(user);
    int raised = 0, n = 0;
    for (size_t i = 0; i < plain.size(); ++i)
        if (plain[i] < 200) ++n, raised += ub[i] == plain[i] + 10;
    CHECK(raised == n);
    Appearance gain = no_noise();
    gain.gain = {1, 1, 0};
    std::vector<uint8_t> g = r.background_frame(gain);
    for (size_t i = 2; i < g.size(); i += 3) REQUIRE(g[i] == 0);
    user.background.resize(5);
    CHECK_THROWS_AS(r.background_frame(user), Error);
}
