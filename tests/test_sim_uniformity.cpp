// SPEC section 5's uniform / non-uniform subset rule (measure_uniformity).
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "engine/io/mesh.h"
#include "engine/sim/uniformity.h"

using namespace vtloc;

namespace {

// A closed UV sphere of radius r: `seg` slices around z, `rings` bands from pole to pole, no vertex normals.
io::TriangleMesh uv_sphere(float r, int seg, int rings) {
    io::TriangleMesh m;
    const double pi = std::acos(-1.0);
    // push_back, not insert of a braced list into the empty vector: GCC 12 -Wstringop-overflow false positive.
    auto vertex = [&](double x, double y, double z) {
        m.positions.push_back(float(x));
        m.positions.push_back(float(y));
        m.positions.push_back(float(z));
    };
    vertex(0, 0, r);
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < seg; ++j) {
            double th = pi * i / rings, ph = 2 * pi * j / seg;
            vertex(r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th));
        }
    vertex(0, 0, -r);
    const uint32_t south = uint32_t(m.vertex_count() - 1);
    auto at = [&](int ring, int j) { return uint32_t(1 + (ring - 1) * seg + (j % seg)); };
    for (int j = 0; j < seg; ++j) {
        m.triangles.insert(m.triangles.end(), {0, at(1, j), at(1, j + 1)});
        for (int i = 1; i + 1 < rings; ++i)
            m.triangles.insert(m.triangles.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        m.triangles.insert(m.triangles.end(), {at(rings - 1, j), south, at(rings - 1, j + 1)});
    }
    return m;
}

HostTensor cloud(const std::vector<std::array<float, 6>>& pts) {
    HostTensor t({int64_t(pts.size()), 6});
    for (size_t i = 0; i < pts.size(); ++i)
        for (int k = 0; k < 6; ++k) t.data[6 * i + size_t(k)] = pts[i][size_t(k)];
    return t;
}

}  // namespace

TEST_CASE("a sampled sphere is uniform", "[sim]") {
    // Face normals of a 48 x 24 sphere: neighbours across a facet edge differ by ~0.13 over ~0.05.
    HostTensor pts = io::sample_surface(uv_sphere(25.0f, 48, 24), 1024, 123, "sphere");
    sim::Uniformity u = sim::measure_uniformity(pts);
    CHECK(u.uniform);
    CHECK(u.share_below > 0.95);
    // The rule is scale-free: the same cloud in other units gives the same share.
    for (size_t i = 0; i < pts.data.size(); ++i)
        if (i % 6 < 3) pts.data[i] *= 1000.0f;
    CHECK(sim::measure_uniformity(pts).share_below == Approx(u.share_below).margin(2.0 / 1024));
}

TEST_CASE("close points with alternating normals are non-uniform", "[sim]") {
    // A 32 x 32 grid, spacing 1 (1/21.9 normalised), normals +z / -z in a checkerboard:
    // every nearest neighbour has the opposite normal, dn = 2 * 21.9 ~ 44 >= 30.
    std::vector<std::array<float, 6>> checker, flat;
    for (int i = 0; i < 32; ++i)
        for (int j = 0; j < 32; ++j) {
            float nz = (i + j) % 2 ? -1.0f : 1.0f;
            checker.push_back({float(i), float(j), 0, 0, 0, nz});
            flat.push_back({float(i), float(j), 0, 0, 0, 1});
        }
    sim::Uniformity u = sim::measure_uniformity(cloud(checker));
    CHECK_FALSE(u.uniform);
    CHECK(u.share_below == 0.0);
    // The same points with one normal: every dn is 0.
    u = sim::measure_uniformity(cloud(flat));
    CHECK(u.uniform);
    CHECK(u.share_below == 1.0);
}

TEST_CASE("uniformity share on tiny hand cases is exact", "[sim]") {
    // A-B close with equal normals (dn 0); C-D 0.02 apart with opposite normals
    // (dn = 2 / (0.02 / 1.06) ~ 106); E's nearest is B, same normal (dn 0): 3 of 5.
    sim::Uniformity u = sim::measure_uniformity(cloud({{-1, 0, 0, 0, 0, 1},
                                                       {-0.98f, 0, 0, 0, 0, 1},
                                                       {0.98f, 0, 0, 0, 0, 1},
                                                       {1, 0, 0, 0, 0, -1},
                                                       {-0.3f, 0.2f, 0, 0, 0, 1}}));
    CHECK(u.share_below == 0.6);
    CHECK_FALSE(u.uniform);
    // Coincident points: equal normals give dn = 0, different ones dn = inf.
    u = sim::measure_uniformity(cloud({{0, 0, 0, 0, 0, 1}, {0, 0, 0, 0, 0, 1}, {5, 0, 0, 1, 0, 0}, {5, 0, 0, 0, 1, 0}}));
    CHECK(u.share_below == 0.5);
    CHECK_FALSE(u.uniform);
    // 7 of 10 below is exactly the 70 % boundary, which counts as uniform. Groups 10 apart:
    // a triple 0, 0.01, 0.03 with normals +z +z -z (2 below: the last one's nearest is the
    // middle one), two equal pairs (4 below), and a triple -z +z +z (1 below: the first two
    // are each other's nearest, with opposite normals).
    u = sim::measure_uniformity(cloud({{0, 0, 0, 0, 0, 1},
                                       {0.01f, 0, 0, 0, 0, 1},
                                       {0.03f, 0, 0, 0, 0, -1},
                                       {10, 0, 0, 0, 0, 1},
                                       {10.01f, 0, 0, 0, 0, 1},
                                       {20, 0, 0, 1, 0, 0},
                                       {20.01f, 0, 0, 1, 0, 0},
                                       {30, 0, 0, 0, 0, -1},
                                       {30.01f, 0, 0, 0, 0, 1},
                                       {30.03f, 0, 0, 0, 0, 1}}));
    CHECK(u.share_below == 0.7);
    CHECK(u.uniform);
}

TEST_CASE("measure_uniformity refuses unusable clouds", "[sim]") {
    CHECK_THROWS_AS(sim::measure_uniformity(HostTensor({1, 6})), vtloc::Error);
    CHECK_THROWS_AS(sim::measure_uniformity(HostTensor({4, 3})), vtloc::Error);
    HostTensor t({2, 6});
    t.data[0] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_AS(sim::measure_uniformity(t), vtloc::Error);
}
