// Procedural training objects. The toothed ones are non-uniform by SPEC
// section 5's rule because most of their area is covered by sharp features
// far finer than the spacing of 1024 samples, so a sample's nearest neighbour
// usually lies on a face with another normal: on the far side of a thin tooth,
// on the next pyramid face, across a thread crest.
#include "engine/sim/shapes.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include "base/error.h"
#include "engine/sim/everyday_shapes.h"
#include "engine/sim/mesh_builder.h"
#include "engine/sim/primitives.h"

namespace vtloc::sim {

namespace {

using io::TriangleMesh;
using mesh::P2;

// ---- uniform solids -------------------------------------------------------

TriangleMesh box() {
    return mesh::slab({-50, 50}, {-30, 30}, [](size_t, size_t) { return 20.0; }, [](size_t, size_t) { return -20.0; });
}

TriangleMesh cylinder() { return mesh::revolve({{30, -50}, {30, 50}}, 96); }

std::vector<P2> arc(double cz, double r, double a0, double a1, int n) {
    std::vector<P2> p;
    for (int i = 0; i <= n; ++i) {
        double a = a0 + (a1 - a0) * i / n;
        p.push_back({std::abs(r * std::cos(a)) < 1e-9 ? 0.0 : r * std::cos(a), cz + r * std::sin(a)});
    }
    return p;
}

TriangleMesh sphere() { return mesh::revolve(arc(0, 50, -M_PI / 2, M_PI / 2, 48), 96); }

TriangleMesh cone() { return mesh::revolve({{40, 0}, {0, 100}}, 96); }

TriangleMesh torus() {
    std::vector<P2> circle;
    for (int i = 0; i < 48; ++i) {
        double a = 2 * M_PI * i / 48;
        circle.push_back({50 + 15 * std::cos(a), 15 * std::sin(a)});
    }
    return mesh::revolve_closed(circle, 96);
}

TriangleMesh capsule() {
    std::vector<P2> p = arc(-40, 20, -M_PI / 2, 0, 24), top = arc(40, 20, 0, M_PI / 2, 24);
    p.insert(p.end(), top.begin(), top.end());
    return mesh::revolve(p, 96);
}

// ---- flat toothed outlines, extruded --------------------------------------

// Outline of a bar [0, len] x [0, height] with `count` teeth of width w at
// pitch p (first at x0) hanging below y = 0 by `depth`, pointed over `tip`.
std::vector<P2> comb_outline(double len, double height, double x0, double p, double w, int count, double depth,
                             double tip) {
    std::vector<P2> o{{0, height}, {0, 0}};
    for (int k = 0; k < count; ++k) {
        double x = x0 + k * p;
        o.insert(o.end(), {{x, 0}, {x, -depth + tip}, {x + w / 2, -depth}, {x + w, -depth + tip}, {x + w, 0}});
    }
    o.insert(o.end(), {{len, 0}, {len, height}});
    return o;
}

// A pocket comb: 70 teeth 1 mm wide at 2 mm pitch, 3 mm thick.
TriangleMesh comb_fine() { return mesh::extrude(comb_outline(150, 14, 5, 2, 1, 70, 26, 0.6), -1.5, 1.5); }

// A wide-toothed comb: 2 mm teeth at 4 mm pitch, 4 mm thick.
TriangleMesh comb_coarse() { return mesh::extrude(comb_outline(180, 20, 5, 4, 2, 43, 34, 1.2), -2, 2); }

// A flat four-tine table fork, 2.5 mm thick, tines 2.2 mm wide with 3 mm gaps.
TriangleMesh fork() {
    std::vector<P2> o{{0, -6}, {110, -4}, {125, -3}, {140, -9}, {148, -9.5}};
    const double w = 2.2, g = 3.0, y0 = -(4 * w + 3 * g) / 2;
    for (int k = 0; k < 4; ++k) {
        double a = y0 + k * (w + g), b = a + w;
        o.insert(o.end(), {{190, a + 0.4}, {190, b - 0.4}});  // rounded-off tips
        if (k < 3) o.insert(o.end(), {{190 - 0.4, b}, {152, b}, {152, b + g}, {190 - 0.4, b + g}});
    }
    o.insert(o.end(), {{148, 9.5}, {140, 9}, {125, 3}, {110, 4}, {0, 6}});
    return mesh::extrude(o, -1.25, 1.25);
}

// Afro pick: 14 teeth 2.5 mm wide, 110 mm long, on a 70 x 60 mm handle.
TriangleMesh hair_pick() {
    std::vector<P2> o = comb_outline(70, 60, 2.25, 5, 2.5, 14, 110, 2);
    return mesh::extrude(o, -2, 2);
}

// A hand-saw blade, 1.2 mm thick, with 2.5 mm rip teeth along its lower edge.
TriangleMesh saw_blade() {
    std::vector<P2> o{{220, 50}, {0, 40}, {0, 0}};
    for (int k = 0; k < 88; ++k) {
        double x = k * 2.5;
        o.insert(o.end(), {{x + 1.8, -2.2}, {x + 2.5, 0}});
    }
    o.pop_back();
    o.push_back({220, 0});
    return mesh::extrude(o, -0.6, 0.6);
}

// Gear with `teeth` trapezoid teeth of module m, face width `width`.
TriangleMesh gear(int teeth, double m, double width) {
    double r = teeth * m / 2, rt = r + m, rr = r - 1.25 * m, a = 2 * M_PI / teeth;
    std::vector<P2> o;
    auto polar = [&](double rad, double ang) { o.push_back({rad * std::cos(ang), rad * std::sin(ang)}); };
    for (int k = 0; k < teeth; ++k) {
        double c = k * a;
        polar(rr, c - 0.30 * a);
        polar(rt, c - 0.12 * a);
        polar(rt, c + 0.12 * a);
        polar(rr, c + 0.30 * a);
    }
    return mesh::extrude(o, -width / 2, width / 2);
}

// A plain spur gear stays uniform: its flat faces outweigh the tooth flanks.
TriangleMesh spur_gear() { return gear(46, 2.5, 30); }

// ---- slabs with textured faces --------------------------------------------

std::vector<double> steps(double a, double b, double step) {
    std::vector<double> v;
    int n = int(std::lround((b - a) / step));
    for (int i = 0; i <= n; ++i) v.push_back(a + (b - a) * i / n);
    return v;
}

// Rasp: 2 mm pyramids, 1.2 mm high, on both faces of a 160 x 30 x 5 mm bar.
TriangleMesh rasp() {
    auto xs = steps(-80, 80, 1.0), ys = steps(-15, 15, 1.0);
    auto tooth = [](size_t i, size_t j) { return (i % 2 == 1 && j % 2 == 1) ? 1.2 : 0.0; };
    return mesh::slab(xs, ys, [&](size_t i, size_t j) { return 2.5 + tooth(i, j); },
                      [&](size_t i, size_t j) { return -2.5 - tooth(i, j); });
}

// Single-cut file: transverse saw-tooth ridges, 1.5 mm pitch, both faces.
TriangleMesh file() {
    std::vector<double> xs;
    std::vector<double> h;
    for (int k = 0; k < 100; ++k) {
        xs.insert(xs.end(), {-75 + 1.5 * k, -75 + 1.5 * k + 1.1});
        h.insert(h.end(), {0.0, 0.8});
    }
    xs.push_back(75);
    h.push_back(0.0);
    return mesh::slab(xs, {-12, 12}, [&](size_t i, size_t) { return 2.5 + h[i]; },
                      [&](size_t i, size_t) { return -2.5 - h[i]; });
}

// Corrugated sheet: 1 mm thick, zig-zag of 4 mm pitch and 3 mm peak to peak.
TriangleMesh corrugated_plate() {
    auto xs = steps(-75, 75, 2.0);
    auto z = [](size_t i) { return i % 2 ? 1.5 : -1.5; };
    return mesh::slab(xs, {-50, 50}, [&](size_t i, size_t) { return z(i) + 0.5; },
                      [&](size_t i, size_t) { return z(i) - 0.5; });
}

// Grid coordinates for `count` columns of width w at pitch p from x0 over
// [0, len]: each column edge repeats its coordinate (a vertical step);
// `inside` tells which vertices sit on a column's top.
void column_grid(double len, double x0, double p, double w, int count, std::vector<double>& xs,
                 std::vector<bool>& inside) {
    xs = {0};
    inside = {false};
    for (int k = 0; k < count; ++k) {
        double a = x0 + k * p;
        xs.insert(xs.end(), {a, a, a + w, a + w});
        inside.insert(inside.end(), {false, true, true, false});
    }
    xs.push_back(len);
    inside.push_back(false);
}

// Brush: 40 x 10 tufts, 2 mm square and 22 mm long, on a 150 x 40 x 10 block.
TriangleMesh brush() {
    std::vector<double> xs, ys;
    std::vector<bool> ix, iy;
    column_grid(150, 1.5, 3.75, 2, 40, xs, ix);
    column_grid(40, 1.25, 3.75, 2, 10, ys, iy);
    return mesh::slab(xs, ys, [&](size_t i, size_t j) { return ix[i] && iy[j] ? 32.0 : 10.0; },
                      [](size_t, size_t) { return 0.0; });
}

// LEGO-like plate with square studs: 2 mm studs, 1.5 mm high, 4 mm pitch.
TriangleMesh studded_plate() {
    std::vector<double> xs, ys;
    std::vector<bool> ix, iy;
    column_grid(128, 1, 4, 2, 32, xs, ix);
    column_grid(64, 1, 4, 2, 16, ys, iy);
    return mesh::slab(xs, ys, [&](size_t i, size_t j) { return ix[i] && iy[j] ? 4.7 : 3.2; },
                      [](size_t, size_t) { return 0.0; });
}

// Pin-fin heat sink: 1.5 mm square pins, 15 mm tall at 3 mm pitch, on a
// long 120 x 39 mm base (on a square base of this size it comes out uniform).
TriangleMesh pin_heatsink() {
    std::vector<double> xs, ys;
    std::vector<bool> ix, iy;
    column_grid(120, 0.75, 3, 1.5, 40, xs, ix);
    column_grid(39, 0.75, 3, 1.5, 13, ys, iy);
    return mesh::slab(xs, ys, [&](size_t i, size_t j) { return ix[i] && iy[j] ? 19.0 : 4.0; },
                      [](size_t, size_t) { return 0.0; });
}

// ---- toothed solids of revolution -----------------------------------------

// Sprocket cassette: 12 sprockets of 120 teeth (tip radius 55 down to 44 mm),
// 1.2 mm thick at 2.5 mm pitch on a 40 mm hub. Thin toothed discs facing each
// other make it non-uniform where a single thick gear is not.
TriangleMesh gear_cassette() {
    std::vector<double> zs;
    std::vector<double> rim;  // tip radius of the sprocket at each z row, 0 = hub
    for (int s = 0; s < 12; ++s) {
        double z0 = 2.5 * s, z1 = z0 + 1.2, r = 55 - 1.0 * s;
        if (s > 0) zs.push_back(z0), rim.push_back(0);
        zs.insert(zs.end(), {z0, z1});
        rim.insert(rim.end(), {r, r});
        if (s < 11) zs.push_back(z1), rim.push_back(0);
    }
    // 4 columns per tooth: two at the tip, two at the root (2 mm deeper).
    return mesh::radial_tube(4 * 120, zs, [&](size_t i, size_t k) {
        if (rim[k] == 0) return 40.0;
        return i % 4 < 2 ? rim[k] : rim[k] - 2.0;
    });
}

// Bolt: round head, then a V thread 1.2 mm deep at 2 mm pitch (stacked rings
// rather than a helix: the same crests and flanks for touches and the rule).
TriangleMesh bolt() {
    std::vector<P2> p{{0, -10}, {12, -10}, {13, -9}, {13, 0}, {6.8, 0}};
    for (int k = 0; k < 50; ++k) p.insert(p.end(), {{8, 2.0 * k + 1}, {6.8, 2.0 * k + 2}});
    p.insert(p.end(), {{6, 100.8}, {0, 100.8}});
    return mesh::revolve(p, 96);
}

// Knurled handle: diamond pyramids about 2 mm wide, 1.2 mm high, with a
// 1 mm chamfer row at each end.
TriangleMesh knurled_cylinder() {
    const int n = 126;  // half-steps around: 63 pyramids of ~2 mm at r = 20
    auto zs = steps(-50, 50, 1.0);
    return mesh::radial_tube(n, zs, [&](size_t i, size_t k) {
        bool apex = i % 2 == 1 && k % 2 == 1;
        return (k == 0 || k + 1 == zs.size()) ? 19.0 : apex ? 21.2 : 20.0;
    });
}

// Ridged grip: 80 axial ridges of 2.4 mm depth, flat ends.
TriangleMesh ridged_cylinder() {
    auto zs = std::vector<double>{-60, 60};
    return mesh::radial_tube(160, zs, [](size_t i, size_t) { return i % 2 ? 25.0 : 22.6; });
}

// ---- smooth, without symmetry ---------------------------------------------

// A potato, 100 mm long: an ellipsoid with nine smooth bumps and dents 14-30 mm
// across, so the curvature changes at the sensor's scale everywhere and no
// rotation maps it onto itself. The demo's sequence localises on it.
TriangleMesh potato() {
    struct Bump {
        double x, y, z, height, width;  // direction (unnormalised), relative height, angular width (rad)
    };
    static const Bump bumps[] = {{1, 0.2, 0.1, 0.10, 0.45},  {-0.8, 0.5, 0.3, 0.08, 0.35}, {0.2, 1, -0.2, -0.07, 0.40},
                                 {0.3, -0.9, 0.4, 0.09, 0.30}, {-0.2, -0.3, 1, 0.12, 0.50}, {0.5, 0.4, -1, -0.06, 0.35},
                                 {-0.6, -0.7, -0.4, 0.07, 0.30}, {0.7, -0.3, 0.8, -0.05, 0.28}, {-1, 0, -0.5, 0.06, 0.40}};
    TriangleMesh m = make_icosphere(1.0, 5);
    const double axes[3] = {50, 34, 29};
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        float* p = &m.positions[3 * v];
        double r = 1;
        for (const Bump& b : bumps) {
            const double n = std::sqrt(b.x * b.x + b.y * b.y + b.z * b.z);
            const double c = std::clamp((p[0] * b.x + p[1] * b.y + p[2] * b.z) / n, -1.0, 1.0);
            const double a = std::acos(c);
            r += b.height * std::exp(-0.5 * a * a / (b.width * b.width));
        }
        for (int k = 0; k < 3; ++k) p[k] = float(p[k] * r * axes[k]);
    }
    // The side rounded to float, as when it was computed in float: the demo's potato stays bit for bit.
    const double f = 100.0 / double(float(io::bounds(m).largest_side()));
    for (float& x : m.positions) x = float(x * f);
    m.normals.clear();  // face normals, like every other shape
    return m;
}

struct ShapeDef {
    const char* name;
    double scale_mm;  // largest dimension as built
    std::function<TriangleMesh()> build;
};

// The everyday objects (everyday_shapes.cpp) follow the solids and toothed parts.
std::vector<ShapeDef> with_everyday(std::vector<ShapeDef> defs) {
    for (const EverydayShape& e : everyday_shapes()) defs.push_back({e.name, e.scale_mm, e.build});
    return defs;
}

const std::vector<ShapeDef>& shapes() {
    static const std::vector<ShapeDef> defs = with_everyday({
        {"box", 100, box},
        {"cylinder", 100, cylinder},
        {"sphere", 100, sphere},
        {"cone", 100, cone},
        {"torus", 130, torus},
        {"capsule", 120, capsule},
        {"comb_fine", 150, comb_fine},
        {"comb_coarse", 180, comb_coarse},
        {"fork", 190, fork},
        {"hair_pick", 170, hair_pick},
        {"saw_blade", 220, saw_blade},
        {"spur_gear", 120, spur_gear},
        {"gear_cassette", 110, gear_cassette},
        {"pin_heatsink", 120, pin_heatsink},
        {"rasp", 160, rasp},
        {"file", 150, file},
        {"corrugated_plate", 150, corrugated_plate},
        {"brush", 150, brush},
        {"studded_plate", 128, studded_plate},
        {"bolt", 110.8, bolt},
        {"knurled_cylinder", 100, knurled_cylinder},
        {"ridged_cylinder", 120, ridged_cylinder},
        {"potato", 100, potato},
    });
    return defs;
}

const ShapeDef& find(const std::string& name) {
    for (const auto& d : shapes())
        if (name == d.name) return d;
    std::string known;
    for (const auto& d : shapes()) known += std::string(known.empty() ? "" : ", ") + d.name;
    throw Error("unknown shape '" + name + "' (known: " + known + ")");
}

}  // namespace

std::vector<std::string> shape_names() {
    std::vector<std::string> names;
    for (const auto& d : shapes()) names.push_back(d.name);
    return names;
}

io::TriangleMesh make_shape(const std::string& name) { return find(name).build(); }

double shape_scale_mm(const std::string& name) { return find(name).scale_mm; }

}  // namespace vtloc::sim
