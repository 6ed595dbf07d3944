// Everyday objects at real sizes (mm). Three kinds of construction:
// solids of revolution and star-shaped tubes (cups, bottles, pens), lofts
// along a path (handles, claws, shackles), and flat parts (mesh::sheet)
// whose outline is drawn as a 2D signed distance and whose thickness and
// mid-surface vary (cutlery, keys, a wrench, a remote's buttons). Parts of an
// object are closed meshes joined side by side: sunk 0.5-2 mm into each other
// at a joint so no gap shows, or 0.05-0.2 mm apart where they only lie
// together (scissor blades, a rivet's heads, a peg's spring). Smooth parts are
// tessellated to sag well under 0.1 mm; outlines follow their signed distance
// to a few um.
#include "engine/sim/everyday_shapes.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include "engine/sim/mesh_builder.h"
#include "engine/sim/mesh_parts.h"

namespace vtloc::sim {

namespace {

using io::TriangleMesh;
using mesh::P2;
using mesh::P3;
using Field = std::function<double(double, double)>;

// ---- small geometry helpers -------------------------------------------------

// std::hypot guards against overflow and is several times slower; sizes here are mm.
double norm(double x, double y) { return std::sqrt(x * x + y * y); }
double norm(double x, double y, double z) { return std::sqrt(x * x + y * y + z * z); }

double smooth(double e0, double e1, double x) {  // smoothstep: 0 below e0, 1 above e1
    const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3 - 2 * t);
}

double lerp(double a, double b, double t) { return a + (b - a) * t; }

// 2D signed distances (negative inside) and their combinations.
double circle(double x, double y, double cx, double cy, double r) { return norm(x - cx, y - cy) - r; }

double rect(double x, double y, double cx, double cy, double hx, double hy, double r = 0) {
    const double qx = std::abs(x - cx) - hx + r, qy = std::abs(y - cy) - hy + r;
    return norm(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0) - r;
}

// An ellipse's distance, approximately (exact sign, close to 1 in slope).
double ellipse(double x, double y, double cx, double cy, double a, double b) {
    const double u = (x - cx) / a, v = (y - cy) / b, k0 = norm(u, v), k1 = norm(u / a, v / b);
    return k1 > 0 ? k0 * (k0 - 1) / k1 : -std::min(a, b);
}

// A capsule whose radius runs from ra at a to rb at b.
double taper(double x, double y, P2 a, P2 b, double ra, double rb) {
    const double h = norm(b.x - a.x, b.y - a.y), ux = (b.x - a.x) / h, uy = (b.y - a.y) / h;
    const double px = std::abs(-(x - a.x) * uy + (y - a.y) * ux), py = (x - a.x) * ux + (y - a.y) * uy;
    const double s = (ra - rb) / h, c = std::sqrt(1 - s * s), k = -s * px + c * py;
    if (k < 0) return norm(px, py) - ra;
    if (k > c * h) return norm(px, py - h) - rb;
    return px * c + py * s - ra;
}

double polygon(double x, double y, const std::vector<P2>& v) {
    double d = (x - v[0].x) * (x - v[0].x) + (y - v[0].y) * (y - v[0].y), s = 1;
    for (size_t i = 0, j = v.size() - 1; i < v.size(); j = i++) {
        const double ex = v[j].x - v[i].x, ey = v[j].y - v[i].y, wx = x - v[i].x, wy = y - v[i].y;
        const double t = std::clamp((wx * ex + wy * ey) / (ex * ex + ey * ey), 0.0, 1.0);
        d = std::min(d, (wx - ex * t) * (wx - ex * t) + (wy - ey * t) * (wy - ey * t));
        const bool c1 = y >= v[i].y, c2 = y < v[j].y, c3 = ex * wy > ey * wx;
        if ((c1 && c2 && c3) || (!c1 && !c2 && !c3)) s = -s;
    }
    return s * std::sqrt(d);
}

// Union with a concave fillet of radius r, and a cut with its new corners rounded.
double round_union(double a, double b, double r) {
    return std::max(r, std::min(a, b)) - norm(std::max(r - a, 0.0), std::max(r - b, 0.0));
}
double round_cut(double a, double b, double r) {
    return std::min(-r, std::max(a, -b)) + norm(std::max(r + a, 0.0), std::max(r - b, 0.0));
}

// A rise of `depth` over the region f < 0, its walls sloping over `edge` mm.
double plateau(double f, double depth, double edge) { return depth * (1 - smooth(-edge, 0, f)); }

// The closed loop of a superellipse |x/a|^p + |y/b|^p = 1, n points from +x.
std::vector<P2> superellipse(double a, double b, double p, int n) {
    std::vector<P2> o;
    for (int i = 0; i < n; ++i) {
        const double t = 2 * M_PI * i / n, c = std::cos(t), s = std::sin(t);
        o.push_back({a * std::copysign(std::pow(std::abs(c), 2 / p), c), b * std::copysign(std::pow(std::abs(s), 2 / p), s)});
    }
    return o;
}

// Rings of section(k) (u along `side`, v across the path in its plane) at each point of the path.
TriangleMesh sweep(const std::vector<P3>& path, P3 side, const std::function<std::vector<P2>(size_t)>& section) {
    std::vector<std::vector<P3>> rings;
    for (size_t k = 0; k < path.size(); ++k) {
        const P3 a = path[k > 0 ? k - 1 : 0], b = path[std::min(k + 1, path.size() - 1)];
        const double tl = norm(b.x - a.x, b.y - a.y, b.z - a.z);
        const P3 t{(b.x - a.x) / tl, (b.y - a.y) / tl, (b.z - a.z) / tl};
        const double st = side.x * t.x + side.y * t.y + side.z * t.z;
        P3 u{side.x - st * t.x, side.y - st * t.y, side.z - st * t.z};
        const double ul = norm(u.x, u.y, u.z);
        u = {u.x / ul, u.y / ul, u.z / ul};
        const P3 v{t.y * u.z - t.z * u.y, t.z * u.x - t.x * u.z, t.x * u.y - t.y * u.x};
        std::vector<P3> ring;
        for (const P2& q : section(k))
            ring.push_back({path[k].x + q.x * u.x + q.y * v.x, path[k].y + q.x * u.y + q.y * v.y, path[k].z + q.x * u.z + q.y * v.z});
        rings.push_back(ring);
    }
    return mesh::loft(rings);
}

// How far a section has shrunk towards a rounded end d mm away along the
// path (an elliptical cap of length len): 0 at the end, 1 from len on.
double end_round(double d, double len) { return d >= len ? 1 : std::sqrt(std::max(0.0, 1 - (1 - d / len) * (1 - d / len))); }

std::vector<P2> scaled(std::vector<P2> v, double f, P2 shift = {0, 0}) {
    for (P2& p : v) p = {shift.x + f * p.x, shift.y + f * p.y};
    return v;
}

// A sheet's outline: where shape < 0 in the box lo..hi, traced every `step` mm.
void outline(mesh::SheetSpec& s, Field shape, P2 lo, P2 hi, double step) {
    s.shape = std::move(shape);
    s.lo = lo, s.hi = hi, s.step = step;
}

// A sheet drawn in the x-z plane, its thickness along y.
P3 yz_swapped(const P3& p) { return {p.x, p.z, p.y}; }

Symmetry about_z(int order) {
    Symmetry s;
    s.order = order;
    return s;
}

Symmetry about_x(int order) {
    Symmetry s;
    s.axis = {1, 0, 0};
    s.order = order;
    return s;
}

// ---- kitchen: solids of revolution ---------------------------------------------

// A 95 mm mug: 3.5 mm wall, foot ring, rounded rim; a D handle of 12 x 7 mm
// oval section whose ends flare and sink 1.3 mm into the wall.
TriangleMesh mug() {
    TriangleMesh body = mesh::revolve(
        mesh::rounded({{0, 2}, {31, 2}, {33, 0}, {41, 0}, {41, 95}, {37.5, 95}, {37.5, 6}, {0, 6}}, {0, 0.8, 0.8, 4, 1.7, 1.7, 4, 0}),
        192);
    std::vector<P3> path{{39.7, 0, 80}};
    for (int i = 0; i <= 96; ++i) {
        const double t = M_PI / 2 - M_PI * i / 96, c = std::cos(t), s = std::sin(t);
        path.push_back({41 + 27 * std::pow(std::max(c, 0.0), 1 / 1.3), 0, 53 + 27 * std::copysign(std::pow(std::abs(s), 1 / 1.3), s)});
    }
    path.push_back({39.7, 0, 26});
    TriangleMesh handle = sweep(path, {0, 1, 0}, [&](size_t k) {
        const double e = double(std::min(k, path.size() - 1 - k)), f = 1 + 0.25 * std::exp(-e * e / 40);
        return superellipse(6 * f, 3.6 * f, 3, 48);
    });
    return mesh::join({body, handle});
}

// A 90 mm tumbler, 75 mm across the rim, tapering to a foot ring.
TriangleMesh cup() {
    return mesh::revolve(mesh::rounded({{0, 3}, {24, 3}, {25.5, 0}, {28, 0}, {37.5, 90}, {35.3, 90}, {25.9, 5}, {0, 5}},
                                       {0, 0.8, 0.8, 2, 1.05, 1.05, 3, 0}),
                         192);
}

// A 150 mm bowl: elliptical wall 3.5 mm thick on a foot ring, rounded rim.
TriangleMesh bowl() {
    const double t0 = std::asin(26.0 / 75);
    std::vector<P2> p = mesh::rounded({{0, 3}, {21, 3}, {22, 0}, {26, 0}, {26, 68 - 64 * std::cos(t0)}}, {0, 0.8, 0.6, 0.6, 0});
    for (int i = 1; i <= 60; ++i) {
        const double t = t0 + (M_PI / 2 - t0) * i / 60;
        p.push_back({75 * std::sin(t), 68 - 64 * std::cos(t)});
    }
    for (int i = 1; i < 16; ++i) p.push_back({73.25 + 1.75 * std::cos(M_PI * i / 16), 68 + 1.75 * std::sin(M_PI * i / 16)});
    for (int i = 0; i <= 80; ++i) {
        const double t = M_PI / 2 * (1 - i / 80.0);
        p.push_back({71.5 * std::sin(t), 68 - 58.5 * std::cos(t)});
    }
    return mesh::revolve(p, 192);
}

// A 24 cm plate: a flat well, a curved rise to a sloping rim, a foot ring.
TriangleMesh dinner_plate() {
    return mesh::revolve(mesh::rounded({{0, 2.8}, {76, 2.8}, {77, 0}, {81, 0}, {82.5, 2.5}, {98, 11.5}, {118.5, 15.1},
                                        {119, 18.3}, {101, 14.7}, {82, 6}, {0, 6}},
                                       {0, 0.6, 0.5, 0.5, 3, 8, 1.5, 1.5, 8, 6, 0}),
                         256);
}

// A 19 cm wine glass: foot, 7.6 mm stem, a tulip bowl with a 1.8 mm wall.
TriangleMesh wine_glass() {
    std::vector<P2> p = mesh::rounded({{0, 0}, {36, 0}, {36, 2.4}, {10, 4.6}, {3.8, 14}, {3.8, 80}, {4.5, 84.3}},
                                      {0, 1.1, 1.1, 4, 4, 3, 0});
    const double t0 = std::asin(4.5 / 42);
    for (int i = 1; i <= 50; ++i) {
        const double t = t0 + (M_PI / 2 - t0) * i / 50;
        p.push_back({42 * std::sin(t), 140 - 56 * std::cos(t)});
    }
    for (int i = 1; i <= 25; ++i) {
        const double z = 140 + 2.0 * i;
        p.push_back({42 - 6 * std::pow((z - 140) / 50, 2), z});
    }
    for (int i = 1; i < 12; ++i) p.push_back({35.1 + 0.9 * std::cos(M_PI * i / 12), 190 + 0.9 * std::sin(M_PI * i / 12)});
    for (int i = 0; i <= 25; ++i) {
        const double z = 190 - 2.0 * i;
        p.push_back({40.2 - 6 * std::pow((z - 140) / 50, 2), z});
    }
    for (int i = 1; i <= 50; ++i) {
        const double t = M_PI / 2 * (1 - i / 50.0);
        p.push_back({40.2 * std::sin(t), 140 - 50 * std::cos(t)});
    }
    return mesh::revolve(p, 192);
}

// A 60 mm light bulb on an E27 base: thread crests 3.6 mm apart (rings, as the
// bolt's), a glass insulator and the foot contact.
TriangleMesh light_bulb() {
    std::vector<P2> p = mesh::rounded({{0, 0}, {3.5, 0}, {4.2, 2.2}, {7.5, 3}, {9, 9}, {12.6, 10}}, {0, 1.2, 0.6, 0.6, 0.6, 0});
    for (int i = 1; i <= 80; ++i) {
        const double z = 10 + 24.0 * i / 80;
        p.push_back({12.6 + 0.6 * std::sin(2 * M_PI * (z - 10) / 3.6), z});
    }
    for (const P2& q : std::vector<P2>{{13.6, 35}, {13.6, 36.5}, {13, 37}}) p.push_back(q);
    // Glass: a Hermite neck from r = 13 to where it meets the 30 mm sphere tangentially.
    const double r1 = std::sqrt(30.0 * 30 - 12 * 12), m0 = 0.15, m1 = 12 / r1, dz = 23;
    for (int i = 1; i <= 24; ++i) {
        const double u = i / 24.0, h00 = 2 * u * u * u - 3 * u * u + 1, h10 = u * u * u - 2 * u * u + u,
                     h01 = -2 * u * u * u + 3 * u * u, h11 = u * u * u - u * u;
        p.push_back({h00 * 13 + h10 * dz * m0 + h01 * r1 + h11 * dz * m1, 37 + dz * u});
    }
    const double a0 = std::asin(-12.0 / 30);
    for (int i = 1; i <= 60; ++i) {
        const double a = a0 + (M_PI / 2 - a0) * i / 60;
        p.push_back({i == 60 ? 0 : 30 * std::cos(a), 72 + 30 * std::sin(a)});
    }
    return mesh::revolve(p, 192);
}

// A 14 cm egg pan, 25 cm with its handle: flared 3 mm wall with a rounded lip,
// and a 117 mm handle of oval section with a hanging hole, rising at 12 degrees. The handle's end is
// sheared parallel to the slanted wall so that all of it sinks into the wall.
TriangleMesh frying_pan() {
    TriangleMesh pan = mesh::revolve(
        mesh::rounded({{0, 0}, {52, 0}, {70, 40}, {66.8, 40}, {50.3, 3}, {0, 3}}, {0, 10, 1.55, 1.55, 9, 0}), 192);
    auto hw = [](double s) { return 10 + 2 * std::clamp(s / 105, 0.0, 1.0); };
    mesh::SheetSpec h;
    outline(h,
        [](double s, double t) {
            const double bar = round_cut(taper(s, t, {-10, 0}, {105, 0}, 10, 12), s, 1.5);
            return std::max(bar, -circle(s, t, 104, 0, 5));
        },
        {-3, -15}, {120, 15}, 0.2);
    h.edge_radius = [](double, double) { return 3.0; };
    h.nominal_thickness = 10;
    h.max_edge = [](double, double) { return 1.2; };
    h.thickness = [&](double s, double t) { return 4 + 6 * std::sqrt(std::max(0.0, 1 - (t / hw(s)) * (t / hw(s)))); };
    const double a = 12 * M_PI / 180, x0 = 52 + 0.45 * 30 - 0.9, z0 = 30;
    TriangleMesh handle = mesh::moved(mesh::sheet(h), [&](const P3& p) {
        const double s = p.x + 0.733 * p.z * (1 - smooth(0, 8, p.x));
        return P3{x0 + s * std::cos(a) - p.z * std::sin(a), p.y, z0 + s * std::sin(a) + p.z * std::cos(a)};
    });
    return mesh::join({pan, handle});
}

// A 21 cm ladle: a hemispherical bowl 78 mm across with a 2 mm wall, and a
// flat handle that lies against the bowl's side, rises and ends in a hook.
TriangleMesh ladle() {
    std::vector<P2> p;
    for (int i = 0; i <= 48; ++i) {
        const double a = -M_PI / 2 + M_PI / 2 * i / 48;
        p.push_back({i == 0 ? 0 : 38 * std::cos(a), 38 + 38 * std::sin(a)});
    }
    for (int i = 1; i < 10; ++i) p.push_back({37 + std::cos(M_PI * i / 10), 38 + std::sin(M_PI * i / 10)});
    for (int i = 0; i <= 48; ++i) {
        const double a = -M_PI / 2 * i / 48;
        p.push_back({i == 48 ? 0 : 36 * std::cos(a), 38 + 36 * std::sin(a)});
    }
    TriangleMesh cup = mesh::revolve(p, 192);
    // The handle's centre line: along the bowl 0.6 mm into its wall, then a turtle walk.
    std::vector<P3> path;
    const double rho = 38 + 1.6 - 0.6;
    for (int i = 0; i <= 12; ++i) {
        const double phi = -25 * M_PI / 180 * (1 - i / 12.0);
        path.push_back({rho * std::cos(phi), 0, 38 + rho * std::sin(phi)});
    }
    double heading = M_PI / 2, x = path.back().x, z = path.back().z;
    for (double s = 2; s <= 212; s += 2) {
        if (s < 30) heading -= (12 * M_PI / 180) / 15;                     // lean outwards
        else if (s > 165 && s < 205) heading -= (150 * M_PI / 180) / 20;  // the hook
        x += 2 * std::cos(heading), z += 2 * std::sin(heading);
        path.push_back({x, 0, z});
    }
    const double length = rho * 25 * M_PI / 180 + 212;
    TriangleMesh handle = sweep(path, {0, 1, 0}, [&](size_t k) {
        const double s = k <= 12 ? rho * 25 * M_PI / 180 * k / 12 : rho * 25 * M_PI / 180 + 2.0 * double(k - 12);
        const double w = 7 + 2.2 * std::sin(M_PI * std::clamp(s / 150, 0.0, 1.0)), f = end_round(length - s, 5);
        return scaled(superellipse(w, 1.6, 4, 40), f);
    });
    return mesh::join({cup, handle});
}

// ---- cutlery: flat parts ----------------------------------------------------

// The raised end of a table piece's handle (mm above the business end).
double handle_rise(double x, double end) { return 10 * std::pow(std::max(0.0, (end - x) / end), 1.8); }

// A 17 cm table spoon: tapered handle, a neck, an elliptical bowl 6.5 mm deep.
TriangleMesh spoon() {
    mesh::SheetSpec s;
    outline(s,
        [](double x, double y) {
            const double handle = std::min(taper(x, y, {13, 0}, {112, 0}, 11.5, 3.4), taper(x, y, {105, 0}, {126, 0}, 3.4, 3.6));
            return round_union(handle, ellipse(x, y, 145, 0, 25, 21), 6);
        },
        {-2, -24}, {173, 24}, 0.2);
    s.edge_radius = [](double, double) { return 0.8; };
    s.nominal_thickness = 2.4;
    s.thickness = [](double x, double) { return 2.4 + 0.6 * smooth(90, 115, x) - 1.2 * smooth(118, 132, x); };
    s.centre = [](double x, double y) {
        const double e = 1 - std::pow((x - 145) / 25, 2) - std::pow(y / 21, 2);
        const double dish = e <= 0 ? 0 : e < 0.15 ? e * e / 0.3 : e - 0.075;  // a C1 ramp, so the rim has no crease
        return handle_rise(x, 120) - 7 * dish;
    };
    return mesh::sheet(s);
}

// An 18.5 cm table fork: handle, neck, a head with four 3.2 mm tines 2.8 mm
// apart that thin and curve up towards their tips.
TriangleMesh table_fork() {
    mesh::SheetSpec s;
    outline(s,
        [](double x, double y) {
            const double handle = std::min(taper(x, y, {12, 0}, {112, 0}, 10.5, 3.1), taper(x, y, {105, 0}, {132, 0}, 3.1, 3.3));
            const double head = polygon(x, y, {{127, -3.3}, {150, -10.6}, {154, -10.6}, {154, 10.6}, {150, 10.6}, {127, 3.3}});
            double tines = 1e9;
            for (double c : {-9.0, -3.0, 3.0, 9.0}) tines = std::min(tines, taper(x, y, {150, c}, {183.8, c}, 1.6, 1.2));
            return round_union(round_union(handle, head, 6), tines, 1.2);
        },
        {-2, -13}, {188, 13}, 0.12);
    s.edge_radius = [](double, double) { return 0.6; };
    s.nominal_thickness = 2.5;
    s.max_edge = [](double, double) { return 0.9; };
    s.thickness = [](double x, double) {
        return 2.5 + 0.4 * smooth(95, 118, x) - 0.8 * smooth(128, 142, x) - 0.4 * smooth(155, 185, x);
    };
    s.centre = [](double x, double) { return handle_rise(x, 118) + 5 * std::pow(std::max(0.0, (x - 138) / 47), 2); };
    return mesh::sheet(s);
}

// The table knife's blade: spine (top) and cutting edge (bottom) heights.
double knife_spine(double x) { return 7 - 9.5 * std::pow(std::max(0.0, (x - 185) / 30), 2); }
double knife_edge(double x) { return -12 + 9.5 * std::pow(std::max(0.0, (x - 160) / 55), 2); }

// A 21 cm table knife: an oval 9.5 mm handle, a bolster, a wedge blade from a
// 2.4 mm spine to a 0.8 mm edge, scalloped (3 mm pitch) over its front half.
TriangleMesh table_knife() {
    // The blade as a polygon grown by 2 mm, which rounds its tip.
    std::vector<P2> top, bottom;
    for (double x = 98; knife_spine(x) - knife_edge(x) > 4.2; x += 2.5) {
        top.push_back({x, knife_spine(x) - 2});
        bottom.push_back({x, knife_edge(x) + 2});
    }
    std::vector<P2> blade(bottom.begin(), bottom.end());
    blade.insert(blade.end(), top.rbegin(), top.rend());
    mesh::SheetSpec s;
    outline(s,
        [&](double x, double y) {
            const double handle = taper(x, y, {10, -2.5}, {94, -2.5}, 8.6, 7.8), bolster = rect(x, y, 100, -2.5, 5, 6.5, 2);
            // The blade's polygon only near the blade (the fillets look 2.5 mm out at most).
            const double box = rect(x, y, 157, -2.5, 60, 10.5);
            double b = box > 3 ? box : polygon(x, y, blade) - 2;
            if (y < -6 && x > 137 && x < 203)
                for (double c = 140; c <= 200; c += 3) b = std::max(b, -circle(x, y, c, knife_edge(c) - 1.1, 1.8));
            return round_union(round_union(handle, bolster, 2), b, 2.5);
        },
        {-1, -16}, {218, 12}, 0.15);
    s.edge_radius = [](double x, double) { return lerp(lerp(2.5, 1.2, smooth(92, 97, x)), 0.3, smooth(103, 108, x)); };
    s.nominal_thickness = 4;
    s.thickness = [](double x, double y) {
        const double handle = 4 + 5.5 * std::sqrt(std::max(0.0, 1 - std::pow((y + 2.5) / 8.6, 2)));
        const double span = std::max(knife_spine(x) - knife_edge(x), 1.0);
        const double wedge = 0.8 + 1.6 * std::clamp((y - knife_edge(x)) / span, 0.0, 1.0);
        return lerp(lerp(handle, 6, smooth(92, 96, x)), wedge, smooth(103, 108, x));
    };
    return mesh::sheet(s);
}

// A 16 cm combination spanner (13 mm): a 12-point ring end and an open end,
// 6 mm thick at the ends and 4.6 mm along the handle. Straight (its open end
// not angled), so a half turn about its long axis maps it onto itself.
TriangleMesh wrench() {
    std::vector<P2> star;  // two hexagons 13 mm across the flats, 30 degrees apart
    for (int k = 0; k < 24; ++k) {
        const double r = k % 2 ? 6.5 / std::cos(M_PI / 12) : 6.5 / std::cos(M_PI / 6), a = k * M_PI / 12;
        star.push_back({r * std::cos(a), r * std::sin(a)});
    }
    mesh::SheetSpec s;
    outline(s,
        [&](double x, double y) {
            double body = round_union(round_union(circle(x, y, 0, 0, 12.5), taper(x, y, {8, 0}, {120, 0}, 6.2, 7.6), 6),
                                      circle(x, y, 132, 0, 16), 6);
            body = std::max(body, -polygon(x, y, star));
            return round_cut(body, std::min(rect(x, y, 150, 0, 18, 6.5), circle(x, y, 132, 0, 6.5)), 1.2);
        },
        {-15, -19}, {151, 19}, 0.15);
    s.edge_radius = [](double, double) { return 0.6; };
    s.nominal_thickness = 6;
    s.thickness = [](double x, double) { return 4.6 + 1.4 * (1 - smooth(14, 30, x)) + 1.4 * smooth(102, 118, x); };
    return mesh::sheet(s);
}

// One half of the scissors, closed: a blade along +x with its cutting edge on
// y = 0 and a handle loop behind the pivot, lying on z = 0.05 and bevelled
// towards the edge on its outer face.
TriangleMesh scissor_half() {
    std::vector<P2> blade;  // grown by 0.8 mm, which rounds the tip
    for (double x = 0; x <= 86; x += 4) blade.push_back({x, 0.8});
    for (double x = 86; x >= 0; x -= 4) blade.push_back({x, 0.8 + 8.5 * (1 - std::pow(x / 90, 1.6)) - 1.6});
    mesh::SheetSpec s;
    outline(s,
        [&](double x, double y) {
            const double b = round_union(polygon(x, y, blade) - 0.8, circle(x, y, 0, 0, 9), 4);
            const double arm = round_union(taper(x, y, {-6, -3}, {-38, -14}, 5.5, 4.5), ellipse(x, y, -52, -19, 17, 12.5), 5);
            const double shape = std::max(round_union(b, arm, 4), -ellipse(x, y, -52, -19, 12, 7.5));
            return std::max(shape, -circle(x, y, 0, 0, 2.6));
        },
        {-72, -34}, {92, 12}, 0.15);
    s.edge_radius = [](double, double) { return 0.5; };
    s.nominal_thickness = 2.4;
    s.thickness = [](double x, double y) {
        const double blade_t = lerp(1.0, 2.4, smooth(0, 3.5, y));
        return lerp(lerp(2.4, 4.5, 1 - smooth(-24, -12, x)), blade_t, smooth(6, 12, x));
    };
    s.centre = [&](double x, double y) { return 0.05 + s.thickness(x, y) / 2; };
    return mesh::sheet(s);
}

// 15 cm scissors opened 20 degrees, the halves in two layers 0.1 mm apart,
// held by a rivet through 5.2 mm holes. The two halves are the same part
// turned over, so a half turn about the long axis maps the scissors onto
// themselves.
TriangleMesh scissors() {
    const TriangleMesh half = scissor_half();
    const double a = 10 * M_PI / 180, c = std::cos(a), sn = std::sin(a);
    TriangleMesh upper = mesh::moved(half, [&](const P3& p) { return P3{c * p.x - sn * p.y, sn * p.x + c * p.y, p.z}; });
    TriangleMesh lower = mesh::moved(half, [&](const P3& p) { return P3{c * p.x - sn * p.y, -(sn * p.x + c * p.y), -p.z}; });
    TriangleMesh rivet = mesh::revolve(
        mesh::rounded({{0, -3.2}, {4.2, -3.2}, {4.2, -2.5}, {2.5, -2.5}, {2.5, 2.5}, {4.2, 2.5}, {4.2, 3.2}, {0, 3.2}},
                      {0, 0.5, 0.2, 0, 0, 0.2, 0.5, 0}),
        96);
    return mesh::join({upper, lower, rivet});
}

// A 55 mm house key: round bow with a key-ring hole, shoulder, a blade with
// five V bitting cuts 1-2.6 mm deep and a milled groove on each face.
TriangleMesh key() {
    const double cuts[5][2] = {{19, 1.5}, {24, 2.6}, {29, 1.0}, {34, 2.2}, {39, 1.8}};
    mesh::SheetSpec s;
    outline(s,
        [&](double x, double y) {
            const double blade = polygon(x, y, {{12, -4.3}, {41, -4.3}, {44, -1.5}, {44, 1.0}, {42, 4.0}, {12, 4.0}});
            double k = round_union(round_union(circle(x, y, 0, 0, 11), rect(x, y, 12.5, -0.3, 2.5, 5.5, 0.5), 2), blade, 1);
            for (const auto& c : cuts)
                k = std::max(k, -polygon(x, y, {{c[0] - c[1] - 0.4, 4.6}, {c[0] + c[1] + 0.4, 4.6},
                                                 {c[0] + 0.3, 4 - c[1]}, {c[0] - 0.3, 4 - c[1]}}));
            return std::max(k, -circle(x, y, -5, 0, 3));
        },
        {-13, -13}, {46, 13}, 0.08);
    auto groove = [](double x, double y, double lo, double hi) {
        return 0.45 * smooth(lo - 0.3, lo, y) * (1 - smooth(hi, hi + 0.3, y)) * smooth(15, 17, x) * (1 - smooth(40, 42, x));
    };
    auto top = [=](double x, double y) { return groove(x, y, -1.2, 0.6); };
    auto bottom = [=](double x, double y) { return groove(x, y, -3.6, -2.4); };
    s.edge_radius = [](double, double) { return 0.3; };
    s.nominal_thickness = 2.3;
    // Fine across each groove's walls, on its own face.
    s.max_edge = [](double x, double y) { return x > 14 && x < 43 && std::abs(std::abs(y + 0.3) - 0.9) < 0.5 ? 0.25 : 0.7; };
    s.max_edge_bottom = [](double x, double y) { return x > 14 && x < 43 && std::abs(std::abs(y + 3.0) - 0.6) < 0.5 ? 0.25 : 0.7; };
    s.thickness = [=](double x, double y) { return lerp(2.4, 2.2, smooth(10, 14, x)) - top(x, y) - bottom(x, y); };
    s.centre = [=](double x, double y) { return (bottom(x, y) - top(x, y)) / 2; };
    return mesh::sheet(s);
}

// A 24 cm slotted turner: a 90 x 72 mm head 2 mm thick (bevelled to 1 mm at
// the front) with four 4.4 mm slots, a neck, and an oval handle with a
// hanging hole, bent up by 18 degrees.
TriangleMesh spatula() {
    mesh::SheetSpec s;
    outline(s,
        [](double x, double y) {
            const double handle = round_union(taper(x, y, {12, 0}, {120, 0}, 12.5, 7.5), taper(x, y, {120, 0}, {152, 0}, 7.5, 12), 3);
            double d = round_union(handle, rect(x, y, 195, 0, 45, 36, 8), 8);
            for (double c : {-18.0, -6.0, 6.0, 18.0}) d = std::max(d, -rect(x, y, 195, c, 28, 2.2, 2.2));
            return std::max(d, -circle(x, y, 13, 0, 4.5));
        },
        {-2, -39}, {243, 39}, 0.2);
    auto hw = [](double x) { return lerp(12.5, 7.5, std::clamp((x - 12) / 108, 0.0, 1.0)); };
    s.edge_radius = [](double x, double) { return lerp(2.5, 0.5, smooth(118, 148, x)); };
    s.nominal_thickness = 4;
    s.max_edge = [](double, double) { return 1.2; };
    s.thickness = [=](double x, double y) {
        const double handle = 4 + 5 * std::sqrt(std::max(0.0, 1 - std::pow(y / hw(x), 2)));
        return lerp(handle, 2 - smooth(228, 240, x), smooth(122, 150, x));
    };
    s.centre = [](double x, double) {
        const double d = 150 - x;
        return d <= 0 ? 0 : d < 10 ? 0.32 * d * d / 20 : 0.32 * (d - 5);
    };
    return mesh::sheet(s);
}

// ---- tools ------------------------------------------------------------------

// A 25 cm claw hammer lying on its side: an oval handle along x sunk 0.6 mm into
// the head's eye block; the head along y, a round face at +y and two curved
// claw prongs with a widening V between them at -y.
TriangleMesh hammer() {
    std::vector<P3> path;
    for (double x = 0; x < 224.6; x += x < 10 || x > 200 ? 0.5 : 4) path.push_back({x, 0, 0});
    path.push_back({224.6, 0, 0});
    TriangleMesh handle = sweep(path, {0, 1, 0}, [&](size_t k) {
        // Narrowing into the eye: the less of it sunk into the head, the less surface hidden there.
        const double x = path[k].x, g = smooth(120, 215, x), flare = 1 - smooth(5, 25, x), eye = 2 * smooth(205, 222, x);
        return scaled(superellipse(15 - 5 * g + 1.5 * flare - eye, 11 - 3.5 * g + flare - eye, 2.4, 64), end_round(x, 8));
    });
    // Head: stations along y, sections in the x-z plane about x = 236.
    std::vector<P3> hp;
    for (double y = -15; y < 42; y += 0.5) hp.push_back({236, y, 0});
    hp.push_back({236, 42, 0});
    TriangleMesh head = sweep(hp, {1, 0, 0}, [&](size_t k) {
        const double y = hp[k].y, neck = smooth(12, 22, y), face = smooth(32, 38, y);
        const double r = lerp(lerp(12, 10, neck), 14, face) - 1.5 * smooth(40.5, 42, y) - 0.8 * (1 - smooth(-15, -14, y));
        const double rz = lerp(lerp(11, 10, neck), 14, face) - 1.5 * smooth(40.5, 42, y) - 0.8 * (1 - smooth(-15, -14, y));
        return superellipse(r, rz, lerp(5, 2, neck), 96);
    });
    auto prong = [&](double side) {
        std::vector<P3> cp{{236, -13, 0}};
        for (int i = 0; i <= 40; ++i) {
            const double a = -0.75 * i / 40;
            cp.push_back({191 + 45 * std::cos(a), -15 + 45 * std::sin(a), 0});
        }
        const double len = 2 + 45 * 0.75;
        return sweep(cp, {0, 0, 1}, [&, side](size_t k) {
            const double s = k == 0 ? 0 : 2 + 45 * 0.75 * double(k - 1) / 40, u = s / len;
            const double gap = 1.5 + 4.5 * u, w = 9 - 5 * u, th = 16 - 11 * u, f = end_round(len - s, 3);
            return scaled(superellipse(w / 2, th / 2, 3, 48), f, {side * (gap / 2 + w / 2), 0});
        });
    };
    return mesh::join({handle, head, prong(1), prong(-1)});
}

// A 20 cm flat screwdriver: a handle with six rounded flutes, a ferrule, a
// 6 mm shaft flattened into a 0.7 mm blade. Star-shaped at every height, so one
// tube; the flutes and the blade share a half turn about the axis.
TriangleMesh screwdriver() {
    struct Row {
        double z, r, flute, half;  // half: the blade's half thickness (0: round)
    };
    std::vector<Row> rows;
    for (int i = 0; i <= 8; ++i) {
        const double a = M_PI / 2 * i / 8;
        rows.push_back({6 - 6 * std::cos(a), 9 + 7 * std::sin(a), 0, 0});
    }
    for (double z = 7; z <= 80; z += z < 14 || z > 72 ? 1 : 6) rows.push_back({z, 16, smooth(6, 12, z) * (1 - smooth(74, 80, z)), 0});
    for (double z = 81; z <= 98; z += 1) rows.push_back({z, 8 + 8 * (0.5 + 0.5 * std::cos(M_PI * (z - 80) / 18)), 0, 0});
    for (const Row& r : std::vector<Row>{{100, 8, 0, 0}, {100.5, 5, 0, 0}, {106, 5, 0, 0}, {107, 3, 0, 0}, {188, 3, 0, 0}})
        rows.push_back(r);
    for (double z = 189; z <= 200; z += 1) rows.push_back({z, 3, 0, lerp(3, 0.35, (z - 188) / 12)});
    std::vector<double> zs;
    for (const Row& r : rows) zs.push_back(r.z);
    const int n = 192;
    return mesh::radial_tube(n, zs, [&](size_t i, size_t k) {
        const double th = 2 * M_PI * double(i) / n, groove = std::pow(0.5 + 0.5 * std::cos(6 * th), 3);
        double r = rows[k].r - 2.5 * rows[k].flute * groove;
        if (rows[k].half > 0 && std::abs(std::sin(th)) > 1e-9) r = std::min(r, rows[k].half / std::abs(std::sin(th)));
        return r;
    });
}

// A padlock 62 mm tall: a rounded 40 x 32 x 18 mm body with a keyhole
// recess on its face and a 7 mm shackle sunk 0.8 mm into its top.
TriangleMesh padlock() {
    auto keyhole = [](double x, double y) { return std::min(circle(x, y, 0, 12, 2.3), rect(x, y, 0, 8.5, 0.9, 3.5)); };
    mesh::SheetSpec s;
    outline(s, [](double x, double y) { return rect(x, y, 0, 16, 20, 16, 5); }, {-22, -2}, {22, 34}, 0.2);
    s.edge_radius = [](double, double) { return 3.0; };
    s.nominal_thickness = 18;
    s.max_edge = [=](double x, double y) { return std::abs(keyhole(x, y)) < 0.6 ? 0.25 : 1.5; };
    s.max_edge_bottom = [](double, double) { return 1.5; };
    s.thickness = [=](double x, double y) { return 18 - plateau(keyhole(x, y), 1.2, 0.25); };
    s.centre = [=](double x, double y) { return -plateau(keyhole(x, y), 1.2, 0.25) / 2; };
    TriangleMesh body = mesh::moved(mesh::sheet(s), yz_swapped);
    std::vector<P3> path;
    for (double z = 31.2; z < 46; z += 1) path.push_back({-12, 0, z});
    for (int i = 0; i <= 48; ++i) path.push_back({-12 * std::cos(M_PI * i / 48), 0, 46 + 12 * std::sin(M_PI * i / 48)});
    for (double z = 45; z >= 31.2; z -= 1) path.push_back({12, 0, z});
    path.push_back({12, 0, 31.2});
    return mesh::join({body, sweep(path, {0, 1, 0}, [](size_t) { return superellipse(3.5, 3.5, 2, 32); })});
}

// A 70 mm wooden clothes peg: two legs with gripping teeth and a line notch at
// the jaws, and the spring's coil (ribbed, as its turns) in notches between
// them with 0.2 mm to spare. The lower leg is the upper one turned over.
TriangleMesh clothes_peg() {
    mesh::SheetSpec s;
    outline(s,
        [](double x, double y) {
            double leg = polygon(x, y, {{1.6, 1.3}, {30, 1.6}, {70.4, 3.0}, {70.4, 6.7}, {30, 6.2}, {1.6, 3.7}}) - 0.8;
            leg = std::max(leg, -circle(x, y, 13, 0, 2.3));
            leg = std::max(leg, -circle(x, y, 38, 0, 4));
            for (double c : {2.5, 4.5, 6.5}) leg = std::max(leg, -circle(x, y, c, 0.2, 0.6));
            return leg;
        },
        {-1, -1}, {73, 9}, 0.08);
    s.edge_radius = [](double, double) { return 1.0; };
    s.nominal_thickness = 9.5;
    s.max_edge = [](double, double) { return 1.0; };
    s.thickness = [](double, double) { return 9.5; };
    const TriangleMesh leg = mesh::sheet(s);
    TriangleMesh upper = mesh::moved(leg, yz_swapped);
    TriangleMesh lower = mesh::moved(leg, [](const P3& p) { return P3{p.x, -p.z, -p.y}; });
    std::vector<P2> coil{{0, -5.4}, {3.0, -5.4}};
    for (int i = 0; i <= 6 * 16; ++i) {
        const double y = -5.0 + 10.0 * i / 96;
        coil.push_back({3.55 + 0.25 * std::cos(2 * M_PI * (y + 5.0) / (10.0 / 6)), y});
    }
    coil.insert(coil.end(), {{3.0, 5.4}, {0, 5.4}});
    TriangleMesh spring = mesh::moved(mesh::revolve(coil, 96), [](const P3& p) { return P3{38 + p.x, p.z, p.y}; });
    return mesh::join({upper, lower, spring});
}

// ---- bottles, pens and pencils: star-shaped tubes ---------------------------

// A 50 cl water bottle, 206 mm: two grip grooves, a shoulder, a neck ring and a
// screw cap with 40 grip ridges (its rotational symmetry).
TriangleMesh bottle() {
    std::vector<double> zs, rs;
    std::vector<bool> ridged;
    auto row = [&](double z, double r, bool cap = false) { zs.push_back(z), rs.push_back(r), ridged.push_back(cap); };
    for (int i = 0; i <= 8; ++i) row(3.5 - 3.5 * std::cos(M_PI / 2 * i / 8), 28.5 + 3.5 * std::sin(M_PI / 2 * i / 8));
    for (double g : {55.0, 135.0}) {
        for (int i = 0; i <= 12; ++i) row(g + 10.0 * i / 12, 32 - 1.2 * std::pow(std::sin(M_PI * i / 12), 2));
    }
    for (int i = 0; i <= 30; ++i) row(150 + i, 13 + 19 * (0.5 + 0.5 * std::cos(M_PI * i / 30)));
    for (const P2& p : std::vector<P2>{{183, 13}, {183.4, 14.6}, {185.6, 14.6}, {186, 13.8}, {187, 13.8}, {187.2, 15}})
        row(p.x, p.y);
    for (double z = 188; z <= 205; z += 1) row(z, 15, true);
    row(205.5, 14.6, true);
    row(205.85, 14.1);
    row(206, 13.4);
    const int n = 240;  // 6 columns a ridge
    return mesh::radial_tube(n, zs, [&](size_t i, size_t k) {
        return rs[k] - (ridged[k] ? 0.55 * (0.5 - 0.5 * std::cos(2 * M_PI * double(i % 6) / 6)) : 0);
    });
}

// A 14 cm ballpoint pen: a ball tip, a grip with 1.5 mm rings, a barrel, a cap
// end and a pocket clip standing 0.5 mm off it.
TriangleMesh pen() {
    std::vector<double> zs, rs;
    auto row = [&](double z, double r) { zs.push_back(z), rs.push_back(r); };
    row(0, 0.45), row(0.6, 0.6), row(1.0, 0.7), row(9, 2.6);
    for (int i = 1; i <= 4; ++i) row(9 + 0.5 * i, 2.6 + 2.4 * std::sin(M_PI / 2 * i / 4));
    for (int i = 1; i <= 18 * 6; ++i) row(11 + 1.5 * i / 6.0, 5.0 - 0.45 * (0.5 - 0.5 * std::cos(2 * M_PI * i / 6.0)));
    row(38.5, 4.8), row(118, 4.8), row(118.2, 5.6), row(119.5, 5.6), row(119.7, 5.3), row(136, 5.3);
    for (int i = 1; i <= 6; ++i) row(136 + 4 * std::sin(M_PI / 2 * i / 6), 2 + 3.3 * std::cos(M_PI / 2 * i / 6));
    TriangleMesh body = mesh::radial_tube(96, zs, [&](size_t, size_t k) { return rs[k]; });
    std::vector<P3> path{{3.8, 0, 134}, {5.5, 0, 133.8}, {6.6, 0, 133}, {6.9, 0, 131.5}};
    for (double z = 130; z >= 102; z -= 2) path.push_back({6.9, 0, z});
    for (const P3& p :
         std::vector<P3>{{6.7, 0, 100.5}, {6.4, 0, 99.3}, {6.35, 0, 98.5}, {6.45, 0, 97.8}, {6.6, 0, 97.4}, {6.75, 0, 97.2}})
        path.push_back(p);
    TriangleMesh clip = sweep(path, {0, 1, 0}, [&](size_t k) {
        return scaled(superellipse(2, 1.1, 4, 32), k + 1 == path.size() ? 0.3 : k + 2 == path.size() ? 0.7 : 1);
    });
    return mesh::join({body, clip});
}

// A 17.5 cm hexagonal pencil (7 mm across the flats), sharpened (the cone cuts
// scallops into the corners), with a ribbed ferrule and an eraser.
TriangleMesh pencil() {
    std::vector<double> zs;
    for (double z = 0; z < 21; z += 0.25) zs.push_back(z);
    for (double z : {155.0, 155.2, 156.5, 157.0, 158.5, 159.0, 160.5, 161.0, 162.8, 163.0, 172.0}) zs.push_back(z);
    for (int i = 1; i <= 6; ++i) zs.push_back(172 + 3 * std::sin(M_PI / 2 * i / 6));
    const int n = 192;  // 32 columns a side
    return mesh::radial_tube(n, zs, [&](size_t i, size_t k) {
        const double z = zs[k], th = 2 * M_PI * double(i) / n;
        const double hex = 3.5 / std::cos(std::fmod(th, M_PI / 3) - M_PI / 6);
        if (z <= 155) return std::min(hex, z < 4 ? 0.35 + 0.65 * z / 4 : 1.0 + (z - 4) * 3.1 / 16);
        if (z <= 163) return (z > 156.2 && z < 157.3) || (z > 158.2 && z < 159.3) || (z > 160.2 && z < 161.3) ? 4.1 : 3.9;
        if (z <= 172) return 3.5;
        return 2.2 + 1.3 * std::cos(M_PI / 2 * (z - 172) / 3);
    });
}

// ---- household ----------------------------------------------------------------

// A 17 cm TV remote: a rounded bar with a domed top and 18 raised buttons
// (1.5 mm): power, a d-pad ring with OK, rockers, mute, a 3 x 4 number pad.
TriangleMesh remote_control() {
    auto buttons = [](double x, double y) {
        double d = std::min(circle(x, y, 70, -12, 4.5), circle(x, y, 38, 0, 6.5));
        d = std::min(d, std::max(circle(x, y, 38, 0, 15), -circle(x, y, 38, 0, 9)));
        d = std::min({d, rect(x, y, 5, -13, 10, 3.8, 2.5), rect(x, y, 5, 13, 10, 3.8, 2.5), circle(x, y, 5, 0, 3.5)});
        for (double r : {-18.0, -30.0, -42.0, -54.0})
            for (double c : {-12.0, 0.0, 12.0}) d = std::min(d, rect(x, y, r, c, 3.8, 4.3, 1.5));
        return d;
    };
    mesh::SheetSpec s;
    outline(s, [](double x, double y) { return rect(x, y, 0, 0, 85, 23, 9); }, {-87, -25}, {87, 25}, 0.25);
    s.edge_radius = [](double, double) { return 5.0; };
    s.nominal_thickness = 18;
    s.max_edge = [=](double x, double y) { return std::abs(buttons(x, y)) < 0.6 ? 0.4 : 1.6; };
    s.max_edge_bottom = [](double, double) { return 2.0; };
    s.thickness = [=](double x, double y) {
        const double body = 15 + 3 * (1 - std::pow(y / 23, 2)) - 2 * (1 - smooth(-85, -30, x));
        const double b = buttons(x, y);
        return body + plateau(b, 1.5, 0.45) + 0.3 * std::clamp(-b / 3, 0.0, 1.0);
    };
    s.centre = [&](double x, double y) { return s.thickness(x, y) / 2; };
    return mesh::sheet(s);
}

// A 116 mm computer mouse: a dome over an egg outline, the two buttons split
// by 0.7 mm grooves, and a ridged scroll wheel standing in a well.
TriangleMesh computer_mouse() {
    auto well = [](double x, double y) { return rect(x, y, 30, 0, 9, 4.2, 1.5); };
    auto lines = [](double x, double y) {  // the button split: distance to the grooves' centre lines
        const double along = x > 8 ? std::abs(y) : 1e9, across = std::abs(y) < 22 ? std::abs(x - 8) : 1e9;
        return std::min(along, across);
    };
    auto dome = [](double x, double y) {
        return 14 + 24 * std::pow(std::max(0.0, 1 - std::pow((x + 15) / 80, 2)), 1.5) * std::max(0.0, 1 - std::pow(y / 34, 2));
    };
    mesh::SheetSpec s;
    outline(s,
        [](double x, double y) { return (norm(x / 58, y / (28.5 - 1.5 * x / 58)) - 1) * 25; },
        {-60, -32}, {60, 32}, 0.25);
    s.edge_radius = [](double, double) { return 3.0; };
    s.nominal_thickness = 30;
    s.max_edge = [=](double x, double y) {
        const bool fine = std::abs(well(x, y)) < 0.8 || lines(x, y) < 1.0 || (std::abs(x - 30) < 12 && std::abs(y) < 5);
        return fine ? 0.4 : 1.5;
    };
    s.max_edge_bottom = [](double, double) { return 2.0; };
    s.thickness = [=](double x, double y) {
        double t = dome(x, y) - plateau(lines(x, y) - 0.35, 0.7, 0.2) - plateau(well(x, y), 3.5, 0.3);
        // The wheel: a 22 mm disc 6.4 mm wide standing 2 mm proud, 1.8 mm ridges.
        const double dx = x - 30, top = dome(30, 0) - 3.5 - 11 + 5.5;
        if (std::abs(dx) < 11 && std::abs(y) < 3.45) {
            const double rim = top + std::sqrt(121 - dx * dx) + 0.3 * std::cos(2 * M_PI * dx / 1.8) - 0.3;
            t = std::max(t, lerp(rim, t, smooth(3.2, 3.45, std::abs(y))));
        }
        return t;
    };
    s.centre = [&](double x, double y) { return s.thickness(x, y) / 2; };
    return mesh::sheet(s);
}

// A 90 mm toy car: a rounded body (side profile with a cabin and wheel arches,
// recessed side windows), four treaded wheels in the arches on two axles.
TriangleMesh toy_car() {
    auto windows = [](double x, double y) {
        return std::min(polygon(x, y, {{31, 24}, {40, 33.5}, {48, 33.5}, {48, 24}}),
                        polygon(x, y, {{50.5, 24}, {50.5, 33.5}, {58.5, 33.5}, {65, 24}}));
    };
    mesh::SheetSpec s;
    outline(s,
        [](double x, double y) {
            const double cabin = polygon(x, y, {{27, 22}, {38, 34}, {60, 34}, {70, 22}}) - 2;
            const double body = round_union(rect(x, y, 45, 15, 45, 9, 6), cabin, 3);
            return round_cut(body, std::min(circle(x, y, 20, 7, 11.5), circle(x, y, 70, 7, 11.5)), 1);
        },
        {-2, 3}, {92, 39}, 0.2);
    s.edge_radius = [](double, double) { return 3.0; };
    s.nominal_thickness = 34;
    s.max_edge = [=](double x, double y) { return std::abs(windows(x, y)) < 0.7 ? 0.3 : 1.6; };
    s.thickness = [=](double x, double y) { return 34 - 2 * plateau(windows(x, y), 1.0, 0.3); };
    std::vector<TriangleMesh> parts{mesh::moved(mesh::sheet(s), yz_swapped)};
    std::vector<double> zs;
    for (int i = 0; i <= 6; ++i) zs.push_back(-4 + 1.5 * (1 - std::cos(M_PI / 2 * i / 6)));
    zs.insert(zs.end(), {-1.8, 1.8});
    for (int i = 6; i >= 0; --i) zs.push_back(4 - 1.5 * (1 - std::cos(M_PI / 2 * i / 6)));
    const TriangleMesh wheel = mesh::radial_tube(144, zs, [&](size_t i, size_t k) {
        const double edge = std::min(zs[k] + 4, 4 - zs[k]), r = 8.8 + 1.2 * std::sin(M_PI / 2 * std::min(edge / 1.5, 1.0));
        return r - (edge >= 1.5 && i % 6 < 2 ? 0.7 : 0);
    });
    const TriangleMesh axle = mesh::revolve({{2, -13}, {2, 13}}, 32);
    for (double cx : {20.0, 70.0}) {
        for (double cy : {-16.0, 16.0})
            parts.push_back(mesh::moved(wheel, [=](const P3& p) { return P3{cx + p.x, cy + p.z, 7 + p.y}; }));
        parts.push_back(mesh::moved(axle, [=](const P3& p) { return P3{cx + p.x, p.z, 7 + p.y}; }));
    }
    return mesh::join(parts);
}

// Each object built once per process (the flat ones take 20-300 ms) and
// copied out: tests and the dataset builder ask for the same objects often.
template <TriangleMesh (*build)()>
TriangleMesh cached() {
    static const TriangleMesh mesh = build();
    return mesh;
}

}  // namespace

const std::vector<EverydayShape>& everyday_shapes() {
    static const std::vector<EverydayShape> defs = {
        {"mug", 112.6, cached<mug>, {}},
        {"cup", 90, cached<cup>, about_z(0)},
        {"bowl", 150, cached<bowl>, about_z(0)},
        {"dinner_plate", 237.5, cached<dinner_plate>, about_z(0)},
        {"wine_glass", 190.9, cached<wine_glass>, about_z(0)},
        {"spoon", 168.5, cached<spoon>, {}},
        {"table_fork", 183.5, cached<table_fork>, {}},
        {"table_knife", 208.6, cached<table_knife>, {}},
        {"ladle", 212.2, cached<ladle>, {}},
        {"spatula", 240.5, cached<spatula>, {}},
        {"frying_pan", 248.6, cached<frying_pan>, {}},
        {"bottle", 206, cached<bottle>, about_z(40)},
        {"light_bulb", 102, cached<light_bulb>, about_z(0)},
        {"wrench", 158.6, cached<wrench>, about_x(2)},
        {"scissors", 150.3, cached<scissors>, about_x(2)},
        {"key", 55, cached<key>, {}},
        {"hammer", 250, cached<hammer>, {}},
        {"screwdriver", 200, cached<screwdriver>, about_z(2)},
        {"padlock", 61.5, cached<padlock>, {}},
        {"clothes_peg", 70.4, cached<clothes_peg>, about_x(2)},
        {"pen", 140, cached<pen>, {}},
        {"pencil", 175, cached<pencil>, about_z(6)},
        {"remote_control", 170, cached<remote_control>, {}},
        {"computer_mouse", 116, cached<computer_mouse>, {}},
        {"toy_car", 90, cached<toy_car>, {}},
    };
    return defs;
}

}  // namespace vtloc::sim
