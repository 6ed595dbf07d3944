#include "engine/sim/symmetry.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "base/error.h"
#include "engine/sim/everyday_shapes.h"

namespace vtloc::sim {

namespace {

Vec3d unit(const Vec3d& a) {
    const double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    return {a[0] / n, a[1] / n, a[2] / n};
}

// Rotation by angle th about unit axis k (Rodrigues), row-major.
Mat3d rotation(const Vec3d& k, double th) {
    const double c = std::cos(th), s = std::sin(th), v = 1 - c;
    return {c + k[0] * k[0] * v,        k[0] * k[1] * v - k[2] * s, k[0] * k[2] * v + k[1] * s,
            k[1] * k[0] * v + k[2] * s, c + k[1] * k[1] * v,        k[1] * k[2] * v - k[0] * s,
            k[2] * k[0] * v - k[1] * s, k[2] * k[1] * v + k[0] * s, c + k[2] * k[2] * v};
}

Mat3d mul(const Mat3d& a, const Mat3d& b) {
    Mat3d o{};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k) o[size_t(r * 3 + c)] += a[size_t(r * 3 + k)] * b[size_t(k * 3 + c)];
    return o;
}

double sq(const Vec3d& a, const Vec3d& b) {
    return (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
}

// Squared distance from p to triangle abc (Ericson's region tests).
double point_triangle_sq(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    auto sub = [](const Vec3d& x, const Vec3d& y) { return Vec3d{x[0] - y[0], x[1] - y[1], x[2] - y[2]}; };
    auto dot = [](const Vec3d& x, const Vec3d& y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
    auto at = [&](double v, double w) {
        return Vec3d{a[0] + v * (b[0] - a[0]) + w * (c[0] - a[0]), a[1] + v * (b[1] - a[1]) + w * (c[1] - a[1]),
                     a[2] + v * (b[2] - a[2]) + w * (c[2] - a[2])};
    };
    const Vec3d ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return sq(p, a);
    const Vec3d bp = sub(p, b);
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return sq(p, b);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return sq(p, at(d1 / (d1 - d3), 0));
    const Vec3d cp = sub(p, c);
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return sq(p, c);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return sq(p, at(0, d2 / (d2 - d6)));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return sq(p, at(1 - w, w));
    }
    const double den = 1 / (va + vb + vc);
    return sq(p, at(vb * den, vc * den));
}

}  // namespace

std::vector<Mat3d> Symmetry::rotations() const {
    if (all) {
        std::vector<Mat3d> out;
        for (const Vec3d& a : {Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}, Vec3d{1, 1, 1}})
            for (int i = 0; i < 24; ++i) out.push_back(rotation(unit(a), 2 * M_PI * i / 24));
        return out;
    }
    const Vec3d k = unit(axis);
    const int n = order == 0 ? 360 : order;
    std::vector<Mat3d> out;
    for (int i = 0; i < n; ++i) out.push_back(rotation(k, 2 * M_PI * i / n));
    if (flip) {
        const Mat3d f = rotation(unit(*flip), M_PI);
        for (int i = 0; i < n; ++i) out.push_back(mul(out[size_t(i)], f));
    }
    return out;
}

Vec3d Symmetry::apply(const Mat3d& R, const Vec3d& p) const {
    const Vec3d d{p[0] - point[0], p[1] - point[1], p[2] - point[2]};
    Vec3d o;
    for (int r = 0; r < 3; ++r)
        o[size_t(r)] = point[size_t(r)] + R[size_t(r * 3)] * d[0] + R[size_t(r * 3 + 1)] * d[1] + R[size_t(r * 3 + 2)] * d[2];
    return o;
}

Symmetry shape_symmetry(const std::string& name) {
    for (const EverydayShape& e : everyday_shapes())
        if (name == e.name) return e.symmetry;
    Symmetry s;  // every revolved shape turns about z through the origin
    const Vec3d x{1, 0, 0}, y{0, 1, 0};
    if (name == "box") s.order = 2, s.flip = x;
    else if (name == "sphere") s.all = true;
    else if (name == "cylinder" || name == "torus" || name == "capsule") s.order = 0, s.flip = x;
    else if (name == "cone" || name == "bolt") s.order = 0;
    else if (name == "ridged_cylinder") s.order = 80, s.flip = x;
    else if (name == "knurled_cylinder") s.order = 63, s.flip = x;
    // The toothed and textured parts built mirror-symmetric (shapes.cpp): a half turn about
    // one of their frame's axes, through their middle, maps them onto themselves.
    else if (name == "spur_gear") s.order = 46, s.flip = x;  // tooth 0 sits on the x axis
    else if (name == "gear_cassette") s.order = 120;        // its sprockets shrink along z: no flip
    else if (name == "rasp") s.order = 2, s.flip = x;
    else if (name == "comb_coarse") s.axis = y, s.order = 2, s.point = {90, -7, 0};  // teeth at 5 + 4k of 180 mm
    else if (name == "corrugated_plate") s.axis = y, s.order = 2;
    else if (name == "file" || name == "fork") s.axis = x, s.order = 2;
    else if (name == "studded_plate") s.order = 2, s.point = {64, 32, 0};
    else if (name == "pin_heatsink") s.order = 2, s.point = {60, 19.5, 0};
    return s;
}

Symmetry scaled_symmetry(const Symmetry& s, double f, const Vec3d& centre) {
    Symmetry o = s;
    for (int k = 0; k < 3; ++k) o.point[size_t(k)] = f * (s.point[size_t(k)] - centre[size_t(k)]);
    return o;
}

double distance_up_to_symmetry(const Symmetry& s, const Vec3d& pred, const Vec3d& truth) {
    if (s.all) return std::abs(std::sqrt(sq(pred, s.point)) - std::sqrt(sq(truth, s.point)));  // the spheres they lie on
    if (s.order == 0) {  // every angle: compare the circles the two points sweep (height h, radius r)
        const Vec3d k = unit(s.axis);
        auto hr = [&](const Vec3d& p) {
            const Vec3d d{p[0] - s.point[0], p[1] - s.point[1], p[2] - s.point[2]};
            const double h = d[0] * k[0] + d[1] * k[1] + d[2] * k[2];
            const Vec3d q{d[0] - h * k[0], d[1] - h * k[1], d[2] - h * k[2]};
            return std::array<double, 2>{h, std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2])};
        };
        const auto a = hr(pred), b = hr(truth);
        double d2 = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]);
        if (s.flip) d2 = std::min(d2, (a[0] + b[0]) * (a[0] + b[0]) + (a[1] - b[1]) * (a[1] - b[1]));
        return std::sqrt(d2);
    }
    // A cyclic group of `order` about the axis (and the flip): in cylindrical coordinates about the
    // axis (h, r, theta) the nearest rotation is the one nearest the angle between the two points,
    // |p - R t|^2 = dh^2 + rp^2 + rt^2 - 2 rp rt cos(residual); the flip maps (h, theta) to
    // (-h, 2 theta_f - theta). Closed form: the eval calls this millions of times.
    const Vec3d k = unit(s.axis);
    Vec3d e1 = s.flip ? unit(*s.flip) : unit(Vec3d{-k[1], k[0], 0});
    if (!s.flip && std::abs(k[2]) > 0.9) e1 = unit(Vec3d{0, -k[2], k[1]});
    const double ke = k[0] * e1[0] + k[1] * e1[1] + k[2] * e1[2];
    e1 = unit(Vec3d{e1[0] - ke * k[0], e1[1] - ke * k[1], e1[2] - ke * k[2]});
    const Vec3d e2{k[1] * e1[2] - k[2] * e1[1], k[2] * e1[0] - k[0] * e1[2], k[0] * e1[1] - k[1] * e1[0]};
    auto cyl = [&](const Vec3d& p) {
        const Vec3d d{p[0] - s.point[0], p[1] - s.point[1], p[2] - s.point[2]};
        const double h = d[0] * k[0] + d[1] * k[1] + d[2] * k[2];
        const double x = d[0] * e1[0] + d[1] * e1[1] + d[2] * e1[2], y = d[0] * e2[0] + d[1] * e2[1] + d[2] * e2[2];
        return std::array<double, 3>{h, std::hypot(x, y), std::atan2(y, x)};
    };
    const auto a = cyl(pred), b = cyl(truth);
    const double step = 2 * M_PI / s.order;
    auto d2 = [&](double hb, double tb) {
        const double dt = a[2] - tb, res = dt - step * std::round(dt / step);
        return (a[0] - hb) * (a[0] - hb) + a[1] * a[1] + b[1] * b[1] - 2 * a[1] * b[1] * std::cos(res);
    };
    double best = d2(b[0], b[2]);
    if (s.flip) best = std::min(best, d2(-b[0], -b[2]));  // theta_f = 0: e1 is the flip axis
    return std::sqrt(std::max(0.0, best));
}

double symmetry_residual_mm(const Symmetry& s, const io::TriangleMesh& mesh, int samples) {
    if (s.none()) return 0;
    // A hash grid of triangles by their bounding boxes, cells of about the mean edge.
    const size_t T = mesh.triangle_count();
    auto vert = [&](size_t t, int c) {
        const float* p = &mesh.positions[3 * size_t(mesh.triangles[3 * t + size_t(c)])];
        return Vec3d{p[0], p[1], p[2]};
    };
    double edge = 0;
    for (size_t t = 0; t < T; ++t) edge += std::sqrt(sq(vert(t, 0), vert(t, 1)));
    const double cell = std::max(0.5, 2 * edge / double(std::max<size_t>(T, 1)));
    // Cells hashed into a flat table of 2^k buckets (CSR: each bucket's triangles in one run);
    // a bucket may mix cells, which only adds triangles to a search.
    using Cell = std::array<int64_t, 3>;
    auto cell_of = [&](const Vec3d& p) {
        return Cell{int64_t(std::floor(p[0] / cell)), int64_t(std::floor(p[1] / cell)), int64_t(std::floor(p[2] / cell))};
    };
    std::vector<std::pair<Cell, Cell>> boxes(T);  // each triangle's cells, lowest and highest
    size_t entries = 0;
    for (size_t t = 0; t < T; ++t) {
        Vec3d lo = vert(t, 0), hi = lo;
        for (int c = 1; c < 3; ++c)
            for (int k = 0; k < 3; ++k) lo[size_t(k)] = std::min(lo[size_t(k)], vert(t, c)[size_t(k)]), hi[size_t(k)] = std::max(hi[size_t(k)], vert(t, c)[size_t(k)]);
        boxes[t] = {cell_of(lo), cell_of(hi)};
        const Cell& l = boxes[t].first;
        const Cell& h = boxes[t].second;
        entries += size_t((h[0] - l[0] + 1) * (h[1] - l[1] + 1) * (h[2] - l[2] + 1));
    }
    size_t buckets = 1;
    while (buckets < 2 * entries) buckets *= 2;
    auto bucket = [&](int64_t x, int64_t y, int64_t z) {
        return size_t(uint64_t((x * 73856093) ^ (y * 19349663) ^ (z * 83492791)) & (buckets - 1));
    };
    auto each_cell = [&](size_t t, const auto& f) {
        const Cell& l = boxes[t].first;
        const Cell& h = boxes[t].second;
        for (int64_t x = l[0]; x <= h[0]; ++x)
            for (int64_t y = l[1]; y <= h[1]; ++y)
                for (int64_t z = l[2]; z <= h[2]; ++z) f(bucket(x, y, z));
    };
    std::vector<uint32_t> start(buckets + 1, 0), tris(entries);
    for (size_t t = 0; t < T; ++t) each_cell(t, [&](size_t b) { ++start[b + 1]; });
    for (size_t b = 0; b < buckets; ++b) start[b + 1] += start[b];
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (size_t t = 0; t < T; ++t) each_cell(t, [&](size_t b) { tris[fill[b]++] = uint32_t(t); });
    // The distance from p to the mesh within one cell around p, else "far" (one cell); it stops
    // early once below `enough`, a bound its caller only needs to know p is under (the worst so far).
    auto nearest = [&](const Vec3d& p, double enough) {
        double best = cell * cell;
        const double stop = enough * enough;
        const Cell c = cell_of(p);
        for (int64_t x = c[0] - 1; x <= c[0] + 1; ++x)
            for (int64_t y = c[1] - 1; y <= c[1] + 1; ++y)
                for (int64_t z = c[2] - 1; z <= c[2] + 1; ++z) {
                    const size_t b = bucket(x, y, z);
                    for (uint32_t i = start[b]; i < start[b + 1]; ++i) {
                        const size_t t = tris[i];
                        best = std::min(best, point_triangle_sq(p, vert(t, 0), vert(t, 1), vert(t, 2)));
                        if (best <= stop && std::sqrt(best) <= enough) return std::sqrt(best);  // sqrt: no rounding past it
                    }
                }
        return std::sqrt(best);
    };
    const HostTensor pts = io::sample_surface(mesh, samples, 12345, "symmetry check");
    std::vector<Mat3d> Rs = s.rotations();
    if (s.order == 0) {  // 24 angles (and their flips) stand for the continuous group
        Symmetry d = s;
        d.order = 24;
        Rs = d.rotations();
    }
    double worst = 0;
    for (const Mat3d& R : Rs)
        for (int64_t i = 0; i < pts.shape[0]; ++i) {
            const Vec3d p{pts.data[size_t(6 * i)], pts.data[size_t(6 * i + 1)], pts.data[size_t(6 * i + 2)]};
            worst = std::max(worst, nearest(s.apply(R, p), worst));  // exact: a point under worst cannot raise it
        }
    return worst;
}

}  // namespace vtloc::sim
