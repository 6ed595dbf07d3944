// Render-and-compare (SPEC 9; engine/track/codebook): the codebook_render and
// codebook_score ops against their CPU references at odd sizes with fixed seeds,
// the maps of known shapes, a rendered touch scoring its own hypothesis near the
// top, the cache (round trip, stale, foreign, corrupt) and bad input by name.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "base/error.h"
#include "engine/io/mesh.h"
#include "engine/ops/build.h"
#include "engine/ops/codebook_math.h"
#include "engine/safetensors.h"
#include "engine/sim/mesh_builder.h"
#include "engine/sim/touch_renderer.h"
#include "engine/track/codebook.h"
#include "tests/harness.h"
#include "tests/io_test_util.h"

using namespace vtloc;

namespace {

// Points on a bumpy sphere of radius ~20 mm with outward normals, and samples on it.
HostTensor bumpy_points(int64_t n, uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> g;
    HostTensor t({n, 6});
    for (int64_t i = 0; i < n; ++i) {
        float v[3] = {g(rng), g(rng), g(rng)};
        const float l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        const float r = 20.0f + 1.5f * std::sin(3 * v[0] / l) * std::cos(2 * v[1] / l);
        for (int k = 0; k < 3; ++k) t.data[size_t(6 * i + k)] = r * v[k] / l, t.data[size_t(6 * i + 3 + k)] = v[k] / l;
    }
    return t;
}

HostTensor samples_of(const HostTensor& pts, int64_t S) {
    HostTensor s({S, 9});
    for (int64_t i = 0; i < S; ++i) {
        const float* p = &pts.data[size_t(6 * ((i * 7919) % pts.shape[0]))];
        const std::array<double, 3> t1 = track::tangent_of({-p[3], -p[4], -p[5]});
        for (int k = 0; k < 6; ++k) s.data[size_t(9 * i + k)] = p[k];
        for (int k = 0; k < 3; ++k) s.data[size_t(9 * i + 6 + k)] = float(t1[size_t(k)]);
    }
    return s;
}

struct RenderCase {
    Graph g;
    TensorMap in;
};

RenderCase render_case(int64_t S, int64_t D, int64_t G, double cell, double coarse, uint32_t seed) {
    const HostTensor pts = bumpy_points(D, seed);
    const track::BinnedPoints b = track::bin_points(pts.data, coarse);
    ops::CodebookRender p;
    p.G = G, p.cell = cell, p.splat = 0.8 * cell, p.cap = 6, p.facing = 0.3, p.coarse = b.coarse, p.max_bin = b.max_bin;
    for (int k = 0; k < 3; ++k) p.origin[k] = b.origin[k], p.dims[k] = b.dims[k];
    RenderCase c;
    const int64_t NB = b.dims[0] * b.dims[1] * b.dims[2];
    c.g.output(ops::codebook_render(c.g, c.g.input("samples", {S, 9}), c.g.input("points", {D, 6}),
                                    c.g.input("bins", {NB, 2}, ElemType::I32), p),
               "heights");
    c.in = {{"samples", samples_of(pts, S)}, {"points", HostTensor({D, 6}, b.points)}, {"bins", HostTensor::from_ints({NB, 2}, b.bins)}};
    return c;
}

// A 60 x 45 x 20 mm prism on an irregular hexagon (test_tracker.cpp's).
io::TriangleMesh prism() { return sim::mesh::extrude({{0, 0}, {50, 0}, {60, 25}, {35, 45}, {10, 38}, {-5, 15}}, 0, 20); }

track::Surface prism_surface(int64_t hypotheses) {
    track::SurfaceOptions o;
    o.target_hypotheses = hypotheses;
    return track::build_surface(io::sample_surface(prism(), 40000, 7, "prism"), true, o, "prism");
}

}  // namespace

TEST_CASE("codebook_render matches the CPU reference", "[op][codebook][codebook_render]") {
    struct Case {
        int64_t S, D, G;
        double cell, coarse;
    };
    // One bin and many; maps of 1, 5 and 27 cells a side; coarse bins that cut the maps short.
    for (const Case& k : {Case{1, 7, 1, 1.0, 100}, Case{13, 3001, 5, 0.7, 8}, Case{37, 20000, 27, 1.0, 21}, Case{5, 5000, 11, 2.0, 3}}) {
        INFO(k.S << " samples, " << k.D << " points, G " << k.G);
        RenderCase c = render_case(k.S, k.D, k.G, k.cell, k.coarse, uint32_t(k.S * 3 + k.G));
        // Heights are minima of identical fp32 values: they agree exactly.
        test::run_gpu_and_compare(c.g, WeightStore{}, c.in, {0, 0});
    }
}

// Random maps [S, G*G] as the scorer reads them: bilinear quads [S, 4 (G+1)^2].
HostTensor random_quads(int64_t S, int64_t G, float cap, uint32_t seed) {
    const HostTensor maps = test::random_tensor({S, G * G}, seed, -1.0f, 3.0f);
    return HostTensor({S, 4 * (G + 1) * (G + 1)}, ops::book::quads_of_maps(maps.data.data(), S, int32_t(G), cap));
}

std::vector<float> quads_of(const std::vector<float>& map, int G, float cap) { return ops::book::quads_of_maps(map.data(), 1, G, cap); }

// A hypothesis scored as the scorer did before percentiles: the plane, pressed to the map's deepest cell.
float score_plane(const ops::book::ScoreParams& s, const float* q, float cs, float sn, const float* m) {
    return ops::book::score_hypothesis(s, ops::book::error_basis(s.R, s.C, false), q, cs, sn, m, ops::book::window_min(s, q, cs, sn),
                                       ops::book::measured_press(m, s.R * s.C, 100));
}

HostTensor spin_table(int64_t NS) { return HostTensor({NS, 2}, ops::book::spin_table(int32_t(NS))); }

TEST_CASE("codebook_window_min matches the CPU reference", "[op][codebook][codebook_window_min]") {
    struct Case {
        int64_t S, G, NS, R, C;
    };
    // Windows inside the map, past its edge (the cap), one cell, one row.
    for (const Case& k : {Case{1, 1, 1, 1, 1}, Case{3, 5, 7, 3, 4}, Case{17, 27, 36, 15, 20}, Case{9, 9, 5, 1, 13}, Case{4, 7, 3, 11, 11}}) {
        INFO(k.S << " samples, G " << k.G << ", " << k.NS << " spins, window " << k.R << "x" << k.C);
        Graph g;
        const int64_t Q = k.G + 1;
        g.output(ops::codebook_window_min(g, g.input("quads", {k.S, 4 * Q * Q}), g.input("spins", {k.NS, 2}), k.R, k.C, 0.9, 1.1, 6.0), "wmin");
        TensorMap in{{"quads", random_quads(k.S, k.G, 6.0f, uint32_t(k.S * k.G + 5))}, {"spins", spin_table(k.NS)}};
        test::run_gpu_and_compare(g, WeightStore{}, in);
    }
}

TEST_CASE("codebook_score matches the CPU reference", "[op][codebook][codebook_score]") {
    struct Case {
        int64_t S, G, NS, R, C;
    };
    for (const Case& k : {Case{1, 1, 1, 1, 1}, Case{3, 5, 7, 3, 4}, Case{17, 27, 36, 15, 20}, Case{9, 9, 5, 1, 13}, Case{2, 6, 4, 2, 2}})
        for (const bool quadratic : {false, true}) {
            INFO(k.S << " samples, G " << k.G << ", " << k.NS << " spins, window " << k.R << "x" << k.C << (quadratic ? ", quadratic" : ", plane"));
            Graph g;
            const int64_t Q = k.G + 1;
            const int quads = g.input("quads", {k.S, 4 * Q * Q}), spins = g.input("spins", {k.NS, 2});
            const int wmin = ops::codebook_window_min(g, quads, spins, k.R, k.C, 0.9, 1.1, 6.0);
            const int measured = g.input("measured", {k.R, k.C}), press_in = g.input("press", {1});
            // Both ways of reading the quads, spins and minima: each against the reference, and bit for bit.
            for (ops::BufferPath path : ops::kBufferPaths)
                g.output(ops::codebook_score(g, quads, spins, measured, wmin, press_in, 0.9, 1.1, 6.0, 2.5, quadratic, "", path),
                         std::string("term.") + ops::path_name(path));
            HostTensor meas = test::random_tensor({k.R, k.C}, uint32_t(k.S + k.R), -0.2f, 1.2f);
            for (float& v : meas.data) v = std::max(0.0f, v);
            const float press = ops::book::measured_press(meas.data.data(), int32_t(k.R * k.C), 95);
            TensorMap in{{"quads", random_quads(k.S, k.G, 6.0f, uint32_t(k.S * k.G))}, {"spins", spin_table(k.NS)}, {"measured", meas},
                         {"press", HostTensor({1}, {press})}};
            const TensorMap got = test::run_gpu_and_compare(g, WeightStore{}, in);
            CHECK(got.at("term.texel").data == got.at("term.storage-buffer").data);
        }
}

// Sum of squares of e less its least-squares fit on the monomials (1, r, c[, r^2, c^2, r c])
// of the window's raw indices, in double by Gram-Schmidt (a monomial that the others
// span, as r^2 on two rows, adds nothing): the definition the one-pass score computes.
double residual_in_double(const std::vector<double>& e, int R, int C, bool quadratic) {
    std::vector<std::vector<double>> basis;
    std::vector<double> res = e;
    for (int k = 0; k < (quadratic ? 6 : 3); ++k) {
        std::vector<double> v(e.size());
        for (int r = 0; r < R; ++r)
            for (int c = 0; c < C; ++c) {
                const double x[6] = {1.0, double(r), double(c), double(r) * r, double(c) * c, double(r) * c};
                v[size_t(r * C + c)] = x[k];
            }
        for (const auto& b : basis) {
            double d = 0;
            for (size_t i = 0; i < v.size(); ++i) d += v[i] * b[i];
            for (size_t i = 0; i < v.size(); ++i) v[i] -= d * b[i];
        }
        double n = 0;
        for (double x : v) n += x * x;
        if (n < 1e-9) continue;
        for (double& x : v) x /= std::sqrt(n);
        double d = 0;
        for (size_t i = 0; i < v.size(); ++i) d += res[i] * v[i];
        for (size_t i = 0; i < v.size(); ++i) res[i] -= d * v[i];
        basis.push_back(v);
    }
    double err = 0;
    for (double x : res) err += x * x;
    return err;
}

TEST_CASE("codebook_score's one pass equals the fit solved in double", "[op][codebook]") {
    // The score takes its fit (the plane, or the plane and r^2, c^2, r c) out by
    // orthogonality: sum e^2 less the projections on a centred basis. Here the definition:
    // the residual after a least-squares fit on the raw monomials, in double. Random maps,
    // spins, tilted and offset presses; windows of one row, one column, two by two and the
    // sensor's 15 x 20.
    std::mt19937 rng(43);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const int G = 27;
    for (const auto& [R, C] : std::vector<std::pair<int, int>>{{15, 20}, {1, 9}, {7, 1}, {4, 6}, {2, 2}})
        for (const bool quadratic : {false, true}) {
            ops::book::ScoreParams s{G, R, C, 1.0f, 0.996f, 8.0f, 1.0f};
            const ops::book::Basis B = ops::book::error_basis(R, C, quadratic);
            for (int trial = 0; trial < 20; ++trial) {
                std::vector<float> map(size_t(G * G)), m(size_t(R * C));
                const float bx = 0.1f * u(rng), by = 0.1f * u(rng), curv = 0.02f * (u(rng) + 1.2f);
                for (int j = 0; j < G; ++j)
                    for (int i = 0; i < G; ++i)
                        map[size_t(j * G + i)] =
                            curv * float((i - 13) * (i - 13) + (j - 13) * (j - 13)) + bx * float(i) + by * float(j) + 0.05f * u(rng);
                for (float& v : m) v = std::max(0.0f, 0.8f + 0.5f * u(rng));
                const float cs = std::cos(float(trial)), sn = std::sin(float(trial));
                const std::vector<float> q = quads_of(map, G, s.cap);
                const float wmin = ops::book::window_min(s, q.data(), cs, sn);
                const float press = ops::book::measured_press(m.data(), R * C, 95);
                std::vector<double> e(size_t(R * C));
                for (int r = 0; r < R; ++r)
                    for (int c = 0; c < C; ++c) {
                        const double w = ops::book::window_depth(s, q.data(), cs, sn, r, c);
                        // The quads' read against plain bilinear interpolation of the map (cap off the grid).
                        const double xx = ((c - (C - 1) / 2.0) * s.win * cs - (r - (R - 1) / 2.0) * s.win * sn) + (G - 1) / 2.0;
                        const double yy = ((c - (C - 1) / 2.0) * s.win * sn + (r - (R - 1) / 2.0) * s.win * cs) + (G - 1) / 2.0;
                        const int ix = int(std::floor(xx)), iy = int(std::floor(yy));
                        auto at = [&](int i, int j) { return i < 0 || j < 0 || i >= G || j >= G ? double(s.cap) : double(map[size_t(j * G + i)]); };
                        const double fx = xx - ix, fy = yy - iy;
                        const double bl =
                            (at(ix, iy) * (1 - fx) + at(ix + 1, iy) * fx) * (1 - fy) + (at(ix, iy + 1) * (1 - fx) + at(ix + 1, iy + 1) * fx) * fy;
                        REQUIRE(std::fabs(w - bl) <= 1e-4 + 1e-4 * std::fabs(bl));
                        e[size_t(r * C + c)] = double(m[size_t(r * C + c)]) - std::max(0.0, double(wmin) + double(press) - w);
                    }
                const double want = -residual_in_double(e, R, C, quadratic) / (double(R * C) * double(press) * press);
                const float got = ops::book::score_hypothesis(s, B, q.data(), cs, sn, m.data(), wmin, press);
                INFO(R << "x" << C << (quadratic ? " quadratic" : " plane") << " trial " << trial << ": " << got << " vs " << want);
                // fp32 sums over <= 300 cells, less the fit's share: ~1e-6 of sum e^2 / (R C press^2).
                CHECK(std::fabs(double(got) - want) <= 1e-5 + 1e-4 * std::fabs(want));
            }
        }
}

TEST_CASE("the measured press is a high percentile of the pressed cells", "[codebook]") {
    // 100 cells: 60 unpressed, 40 pressed at 0.01 .. 0.40 mm, one spike at 2 mm.
    std::vector<float> m(100, 0.0f);
    for (int k = 0; k < 40; ++k) m[size_t(k)] = 0.01f * float(k + 1);
    m[99] = 2.0f;
    // Pressed: deeper than 2 % of 2 mm (0.04): 0.05 .. 0.40 (36 cells) and the spike, 37.
    CHECK(ops::book::measured_press(m.data(), 100, 100) == 2.0f);
    CHECK(ops::book::measured_press(m.data(), 100, 95) == m[size_t(39)]);  // rank ceil(0.95 * 37) = 36 of 37: 0.40
    CHECK(ops::book::measured_press(m.data(), 100, 50) == m[size_t(22)]);  // rank 19 of 37: 0.23
    std::vector<float> none(10, 0.0f);
    CHECK(ops::book::measured_press(none.data(), 10, 95) == 0.0f);
}

TEST_CASE("codebook_score: a map scored against itself is best, and no press is no evidence", "[op][codebook]") {
    const int G = 9, R = 3, C = 5;
    ops::book::ScoreParams s{G, R, C, 1.0f, 1.0f, 6.0f, 1.0f};
    std::vector<float> map(size_t(G * G));
    for (int j = 0; j < G; ++j)
        for (int i = 0; i < G; ++i) map[size_t(j * G + i)] = 0.1f * float((i - 4) * (i - 4)) + 0.05f * float(j);
    // The measured map that hypothesis (map, spin 0) predicts at a 0.6 mm press.
    std::vector<float> m(size_t(R * C));
    float wmin = 6;
    for (int r = 0; r < R; ++r)
        for (int c = 0; c < C; ++c) wmin = std::min(wmin, map[size_t((r + 3) * G + c + 2)]);
    for (int r = 0; r < R; ++r)
        for (int c = 0; c < C; ++c) m[size_t(r * C + c)] = std::max(0.0f, wmin + 0.6f - map[size_t((r + 3) * G + c + 2)]);
    const std::vector<float> q = quads_of(map, G, s.cap);
    CHECK(score_plane(s, q.data(), 1.0f, 0.0f, m.data()) == 0.0f);
    CHECK(score_plane(s, q.data(), 0.0f, 1.0f, m.data()) < -0.01f);  // a quarter turn
    std::vector<float> none(size_t(R * C), 0.0f);
    CHECK(score_plane(s, q.data(), 0.0f, 1.0f, none.data()) == 0.0f);
    CHECK(ops::book::unordered(ops::book::ordered(-2.5f)) == -2.5f);
    CHECK(ops::book::ordered(-1.0f) < ops::book::ordered(-0.5f));
    CHECK(ops::book::ordered(-0.5f) < ops::book::ordered(0.25f));
}

TEST_CASE("codebook_score: the sensor's tilt costs nothing, a bump does", "[op][codebook]") {
    // A press deep enough that the whole 3 x 5 window touches: a tilted sensor (up to 10
    // degrees in our data) adds a plane to the measured map, which is not where the touch was.
    const int G = 9, R = 3, C = 5;
    ops::book::ScoreParams s{G, R, C, 1.0f, 1.0f, 6.0f, 1.0f};
    std::vector<float> map(size_t(G * G));
    for (int j = 0; j < G; ++j)
        for (int i = 0; i < G; ++i) map[size_t(j * G + i)] = 0.1f * float((i - 4) * (i - 4)) + 0.05f * float(j);
    auto window = [&](int r, int c) { return map[size_t((r + 3) * G + c + 2)]; };
    float wmin = 6;
    for (int r = 0; r < R; ++r)
        for (int c = 0; c < C; ++c) wmin = std::min(wmin, window(r, c));
    std::vector<float> tilted(size_t(R * C)), bumped(size_t(R * C));
    for (int r = 0; r < R; ++r)
        for (int c = 0; c < C; ++c) {
            const float own = wmin + 1.0f - window(r, c);
            REQUIRE(own > 0.3f);
            tilted[size_t(r * C + c)] = own + 0.08f * float(r - 1) - 0.06f * float(c - 2);  // tan(3.4 deg) per 1 mm cell
            bumped[size_t(r * C + c)] = own + ((r == 1 && c == 2) ? 0.2f : 0.0f);
        }
    const std::vector<float> q = quads_of(map, G, s.cap);
    const float tilt_score = score_plane(s, q.data(), 1.0f, 0.0f, tilted.data());
    CHECK(tilt_score > -1e-6f);  // only rounding: the plane goes entirely
    CHECK(score_plane(s, q.data(), 1.0f, 0.0f, bumped.data()) < -1e-3f);
    CHECK(score_plane(s, q.data(), 0.0f, 1.0f, tilted.data()) < tilt_score - 1e-3f);  // a quarter turn
}

TEST_CASE("a flat face's codebook map is flat and empty beyond its edge", "[codebook]") {
    // Points on the plane z = 0 (normal +z) over x in [-30, 5]: a sample at the origin
    // looks down -z; cells beyond x = 5 see nothing (the cap).
    std::vector<float> dense;
    for (double x = -30; x <= 5.0001; x += 0.4)
        for (double y = -30; y <= 30.0001; y += 0.4) dense.insert(dense.end(), {float(x), float(y), 0, 0, 0, 1});
    track::Surface s;
    s.dense = dense;
    s.samples = {0, 0, 0, 0, 0, 1, 1, 0, 0};  // t1 = +x
    s.spins = {1, 0};
    s.spacing_mm = 0.4, s.from_mesh = true;
    track::CodebookOptions o;
    const track::Codebook b = track::render_codebook(nullptr, s, o);
    REQUIRE(b.G == 27);
    const int64_t c = (b.G - 1) / 2;
    CHECK(b.heights[size_t(c * b.G + c)] == 0.0f);
    CHECK(b.heights[size_t(c * b.G + c + 4)] == 0.0f);                    // x = 4
    CHECK(b.heights[size_t(c * b.G + c + 7)] == float(o.cap_mm));         // x = 7: off the face
    CHECK(b.heights[size_t(0)] == 0.0f);                                  // a corner, still on the face
    // The same on the GPU.
    const track::Codebook bg = track::render_codebook(&test::gpu(), s, o);
    CHECK(bg.heights == b.heights);
    test::require_no_validation_messages();
}

TEST_CASE("a rendered touch scores its own pose near the top", "[codebook]") {
    const track::Surface s = prism_surface(20000);
    const track::Codebook b = track::render_codebook(&test::gpu(), s, {});
    // The comparison at the maps' 1 mm cells and at 3 mm ones (a ninth of the reads).
    const double cell = GENERATE(1.0, 3.0);
    INFO("comparison cells of " << cell << " mm");
    track::ScoreOptions so;
    so.weight = 1.0, so.cell_mm = cell;
    track::CodebookScorer scorer(&test::gpu(), b, s, so);
    sim::TouchRenderer ren(sim::load_calibration(sim::default_calibration_path()), prism());
    const int64_t S = s.n_samples(), NS = s.n_spin();
    int tested = 0, near_top = 0;
    // Touches at every 97th sample (vertical faces near edges and the top face alike), spin 3 steps.
    for (int64_t i = 0; i < S && tested < 8; i += 97) {
        const float* p = &s.samples[size_t(9 * i)];
        sim::TouchParams tp;
        tp.press_mm = 0.9;
        tp.spin_deg = 3 * 360.0 / NS;
        const sim::Touch t = ren.render({p[0], p[1], p[2]}, {p[3], p[4], p[5]}, tp, sim::Appearance{}, 1);
        if (!t.ok) continue;
        ++tested;
        const std::vector<float> term = scorer.term(t.indentation_mm, ren.calibration().height, ren.calibration().width,
                                                    ren.calibration().mm_per_px);
        REQUIRE(term.size() == size_t(S * NS));
        const float own = term[size_t(i * NS + 3)];
        int64_t better = 0;
        for (float v : term) better += v > own;
        INFO("sample " << i << ": " << better << " of " << term.size() << " hypotheses score better");
        near_top += better <= int64_t(term.size() / 50);  // the top 2 %
    }
    REQUIRE(tested >= 5);
    CHECK(near_top >= tested - 1);
    // The CPU reference gives the same term.
    track::CodebookScorer cpu(nullptr, b, s, so);
    const float* p = &s.samples[0];
    const sim::Touch t = ren.render({p[0], p[1], p[2]}, {p[3], p[4], p[5]}, sim::TouchParams{}, sim::Appearance{}, 1);
    if (t.ok) {
        const auto& cal = ren.calibration();
        const std::vector<float> a = scorer.term(t.indentation_mm, cal.height, cal.width, cal.mm_per_px);
        const std::vector<float> r = cpu.term(t.indentation_mm, cal.height, cal.width, cal.mm_per_px);
        test::require_close(HostTensor({int64_t(a.size())}, a), HostTensor({int64_t(r.size())}, r), {}, "codebook term");
    }
    test::require_no_validation_messages();
}

TEST_CASE("the codebook cache round-trips and refuses stale, foreign and corrupt files by name", "[codebook]") {
    const track::Surface s = prism_surface(4000);
    const std::string path = test::temp_path("prism.codebook");
    std::filesystem::remove(path);
    const track::Codebook a = track::cached_codebook(&test::gpu(), s, {}, path);
    REQUIRE(std::filesystem::exists(path));
    const track::Codebook b = track::cached_codebook(nullptr, s, {}, path);  // read, not rendered
    CHECK(b.heights == a.heights);
    // Another surface: stale.
    const track::Surface other = prism_surface(8000);
    test::require_error([&] { track::load_codebook(path, other); }, {path, "another surface", "delete it"});
    // Other options: stale too.
    track::CodebookOptions o;
    o.cell_mm = 0.5;
    test::require_error([&] { track::load_codebook(path, s, o); }, {path, "other options"});
    // A weight file is not a codebook.
    const std::string foreign = test::temp_path("foreign.codebook");
    write_safetensors(foreign, {TensorBlob::f32("heights", {1, 1}, {0.0f})}, {{"format", "vtloc-weights/1"}});
    test::require_error([&] { track::load_codebook(foreign, s); }, {foreign, "not a vtloc-codebook/1"});
    // Truncated.
    std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
    test::require_error([&] { track::load_codebook(path, s); }, {path});
    // Not tensors at all (a JSON given as the cache): the error says what it likely is.
    const std::string json = test::write_temp("not.codebook", "{\"x\": 1}\n");
    test::require_error([&] { track::load_codebook(json, s); }, {json, "not a codebook cache?"});
    // A directory named as the cache (it exists, so it is read, not written): named, not "out of memory".
    const std::string dir = test::temp_path("a_codebook_dir");
    std::filesystem::create_directories(dir);
    test::require_error([&] { track::cached_codebook(nullptr, s, {}, dir); }, {dir, "is a directory, not a codebook cache"});
    test::require_no_validation_messages();
}

TEST_CASE("render-and-compare refuses sparse clouds and bad maps by name", "[codebook]") {
    // A 1024-point cloud of a 60 mm prism: far below a point per mm^2.
    track::Surface s = track::build_surface(io::sample_surface(prism(), 1024, 7, "prism"), false, {}, "sparse.ply");
    test::require_error([&] { track::render_codebook(nullptr, s, {}); }, {"dense cloud", "per mm^2", "1024 points"});
    // 40,000 points over its ~10,600 mm^2 (about 4 per mm^2) are enough.
    track::SurfaceOptions few;
    few.target_hypotheses = 2000;
    const track::Surface dense = track::build_surface(io::sample_surface(prism(), 40000, 7, "prism"), false, few, "dense.ply");
    // Options out of range are refused before anything is sized from them (a 0 mm cell divides).
    track::CodebookOptions zero;
    zero.cell_mm = 0;
    test::require_error([&] { track::render_codebook(nullptr, dense, zero); }, {"cell 0.1-10 mm"});
    test::require_error([&] { track::render_codebook_rows(nullptr, dense, {0, 1}, zero); }, {"cell 0.1-10 mm"});
    test::require_error([&] { track::render_codebook_rows(nullptr, dense, {dense.n_samples()}, {}); }, {"sample"});
    const track::Codebook all = track::render_codebook(nullptr, dense, {});  // one row of it, rendered alone: the same bits
    REQUIRE(all.G == 27);
    CHECK(all.n_samples() == dense.n_samples());
    CHECK(track::render_codebook_rows(nullptr, dense, {3}, {}) ==
          std::vector<float>(all.heights.begin() + 3 * 27 * 27, all.heights.begin() + 4 * 27 * 27));
    double win = 0;
    test::require_error([&] { track::window_map({1, 2, 3}, 2, 2, 0.1, 1, &win); }, {"3 values for 2 x 2"});
    test::require_error([&] { track::window_map({1, NAN, 3, 4}, 2, 2, 0.1, 1, &win); }, {"NaN"});
    const HostTensor m = track::window_map(std::vector<float>(120 * 160, 0.5f), 120, 160, 0.1245, 1.0, &win);
    CHECK(m.shape == Shape{15, 20});
    CHECK(win == Approx(0.996));
    CHECK(m.data[7] == 0.5f);
}
