#include "engine/sim/mesh_parts.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include "base/error.h"

namespace vtloc::sim::mesh {

namespace {

// std::hypot guards against overflow and is several times slower; sizes here are mm.
double norm(double x, double y) { return std::sqrt(x * x + y * y); }

P3 sub(P3 a, P3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
P3 cross(P3 a, P3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(P3 a, P3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
P3 unit(P3 a) {
    const double n = std::sqrt(dot(a, a));
    return {a.x / n, a.y / n, a.z / n};
}

double cross2(P2 o, P2 a, P2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

double area2(const std::vector<P2>& poly) {
    double s = 0;
    for (size_t i = 0, n = poly.size(); i < n; ++i) s += poly[i].x * poly[(i + 1) % n].y - poly[(i + 1) % n].x * poly[i].y;
    return 0.5 * s;
}

P3 vertex(const io::TriangleMesh& m, uint32_t i) {
    return {m.positions[3 * size_t(i)], m.positions[3 * size_t(i) + 1], m.positions[3 * size_t(i) + 2]};
}

// Caps an end ring: its polygon projected onto the plane across its Newell
// normal, in which the ring runs counter-clockwise, so ear clipping's triangles
// follow the ring's direction; `against` reverses them to pair with the walls.
void cap(Builder& b, const std::vector<P3>& ring, const std::vector<uint32_t>& ids, bool against) {
    P3 n{0, 0, 0};
    for (size_t i = 0; i < ring.size(); ++i) {
        const P3 &a = ring[i], &c = ring[(i + 1) % ring.size()];
        n.x += (a.y - c.y) * (a.z + c.z);
        n.y += (a.z - c.z) * (a.x + c.x);
        n.z += (a.x - c.x) * (a.y + c.y);
    }
    n = unit(n);
    const P3 e1 = unit(std::abs(n.x) < 0.9 ? cross(P3{1, 0, 0}, n) : cross(P3{0, 1, 0}, n)), e2 = cross(n, e1);
    std::vector<P2> flat;
    for (const P3& p : ring) flat.push_back({dot(p, e1), dot(p, e2)});
    const std::vector<uint32_t> tri = triangulate_polygon(flat);
    for (size_t t = 0; t < tri.size(); t += 3) {
        if (against)
            b.triangle(ids[tri[t]], ids[tri[t + 2]], ids[tri[t + 1]]);
        else
            b.triangle(ids[tri[t]], ids[tri[t + 1]], ids[tri[t + 2]]);
    }
}

bool crosses(P2 a, P2 b, P2 c, P2 d) {  // proper crossing of segments ab and cd
    const double d1 = cross2(a, b, c), d2 = cross2(a, b, d), d3 = cross2(c, d, a), d4 = cross2(c, d, b);
    return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

bool same(P2 a, P2 b) { return a.x == b.x && a.y == b.y; }

// Ear clipping that lets a polygon carry collinear points (a resampled
// straight edge): only strictly convex corners are clipped, so no triangle
// comes out flat. Counter-clockwise input; indices into it.
std::vector<uint32_t> ear_clip(const std::vector<P2>& p) {
    if (p.size() < 3) throw Error("triangulate_with_holes: a loop of " + std::to_string(p.size()) + " points");
    std::vector<uint32_t> idx(p.size()), out;
    for (size_t i = 0; i < p.size(); ++i) idx[i] = uint32_t(i);
    auto convex = [&](P2 a, P2 b, P2 c) {
        return cross2(a, b, c) > 1e-9 * norm(b.x - a.x, b.y - a.y) * norm(c.x - b.x, c.y - b.y);
    };
    auto blocked = [&](size_t ia, size_t ib, size_t ic) {
        const P2 a = p[idx[ia]], b = p[idx[ib]], c = p[idx[ic]];
        for (size_t k = 0; k < idx.size(); ++k) {
            const P2 q = p[idx[k]];
            if (k == ia || k == ib || k == ic || same(q, a) || same(q, b) || same(q, c)) continue;
            if (cross2(a, b, q) >= 0 && cross2(b, c, q) >= 0 && cross2(c, a, q) >= 0) return true;
        }
        return false;
    };
    for (size_t i = 0, misses = 0; idx.size() > 3;) {
        const size_t m = idx.size(), ia = (i + m - 1) % m, ic = (i + 1) % m;
        if (convex(p[idx[ia]], p[idx[i]], p[idx[ic]]) && !blocked(ia, i, ic)) {
            out.insert(out.end(), {idx[ia], idx[i], idx[ic]});
            idx.erase(idx.begin() + long(i));
            misses = 0;
            if (i >= idx.size()) i = 0;
        } else {
            if (++misses > m) throw Error("triangulate_with_holes: no ear left (the outline crosses itself?)");
            i = (i + 1) % m;
        }
    }
    out.insert(out.end(), {idx[0], idx[1], idx[2]});
    return out;
}

// Whether direction d from corner p (between a before it and c after it, on a
// counter-clockwise polygon) points into the polygon.
bool into_corner(P2 a, P2 p, P2 c, P2 d) {
    const P2 out{c.x - p.x, c.y - p.y}, back{a.x - p.x, a.y - p.y};
    auto cr = [](P2 u, P2 v) { return u.x * v.y - u.y * v.x; };
    if (cross2(a, p, c) > 0) return cr(out, d) > 0 && cr(d, back) > 0;  // convex
    return !(cr(back, d) >= 0 && cr(d, out) >= 0);
}

}  // namespace

io::TriangleMesh loft(const std::vector<std::vector<P3>>& rings) {
    const size_t k = rings.size(), n = rings.empty() ? 0 : rings[0].size();
    if (k < 2 || n < 3) throw Error("loft: needs at least 2 rings of at least 3 points");
    Builder b;
    std::vector<std::vector<uint32_t>> ids(k);
    std::vector<bool> pole(k);
    for (size_t r = 0; r < k; ++r) {
        if (rings[r].size() != n) throw Error("loft: rings differ in size");
        double spread = 0;
        for (const P3& p : rings[r]) spread = std::max(spread, dot(sub(p, rings[r][0]), sub(p, rings[r][0])));
        pole[r] = spread < 1e-18;
        if (pole[r]) ids[r].assign(n, b.vertex(rings[r][0].x, rings[r][0].y, rings[r][0].z));
        else
            for (const P3& p : rings[r]) ids[r].push_back(b.vertex(p.x, p.y, p.z));
    }
    for (size_t r = 0; r + 1 < k; ++r) {
        const auto &lo = ids[r], &hi = ids[r + 1];
        for (size_t i = 0; i < n; ++i) b.quad(lo[i], lo[(i + 1) % n], hi[(i + 1) % n], hi[i]);
    }
    if (!pole[0]) cap(b, rings[0], ids[0], true);
    if (!pole[k - 1]) cap(b, rings[k - 1], ids[k - 1], false);
    return b.finish();
}

namespace {

// Douglas-Peucker on the open run loop[a..b] (indices taken modulo its size):
// marks the points that stay further than tol from the simplified run.
void simplify_run(const std::vector<P2>& loop, size_t a, size_t b, double tol, std::vector<bool>& keep) {
    const size_t n = loop.size();
    if (b <= a + 1) return;
    const P2 p = loop[a % n], q = loop[b % n];
    const double len = norm(q.x - p.x, q.y - p.y);
    double worst = -1;
    size_t at = a;
    for (size_t i = a + 1; i < b; ++i) {
        const P2 r = loop[i % n];
        const double d = len > 0 ? std::abs(cross2(p, q, r)) / len : norm(r.x - p.x, r.y - p.y);
        if (d > worst) worst = d, at = i;
    }
    if (worst <= tol) return;
    keep[at % n] = true;
    simplify_run(loop, a, at, tol, keep);
    simplify_run(loop, at, b, tol, keep);
}

std::vector<P2> simplify_loop(const std::vector<P2>& loop, double tol) {
    const size_t n = loop.size();
    size_t far = 0;
    for (size_t i = 1; i < n; ++i)
        if (norm(loop[i].x - loop[0].x, loop[i].y - loop[0].y) > norm(loop[far].x - loop[0].x, loop[far].y - loop[0].y))
            far = i;
    std::vector<bool> keep(n, false);
    keep[0] = keep[far] = true;
    simplify_run(loop, 0, far, tol, keep);
    simplify_run(loop, far, n, tol, keep);
    std::vector<P2> out;
    for (size_t i = 0; i < n; ++i)
        if (keep[i]) out.push_back(loop[i]);
    return out;
}

// A signed distance sampled on a grid, for marching squares.
struct Grid {
    P2 lo{0, 0};
    double step = 1;
    int64_t nx = 0, ny = 0;
    std::vector<double> v;
    P2 at(int64_t i, int64_t j) const { return {lo.x + double(i) * step, lo.y + double(j) * step}; }
};

Grid sample_grid(const std::function<double(double, double)>& f, P2 lo, P2 hi, double step) {
    Grid g;
    g.lo = lo, g.step = step;
    g.nx = int64_t(std::ceil((hi.x - lo.x) / step)) + 1, g.ny = int64_t(std::ceil((hi.y - lo.y) / step)) + 1;
    if (g.nx < 2 || g.ny < 2 || g.nx * g.ny > 40000000) throw Error("contour_loops: box or step out of range");
    g.v.resize(size_t(g.nx * g.ny));
    for (int64_t j = 0; j < g.ny; ++j)
        for (int64_t i = 0; i < g.nx; ++i) {
            const double x = f(g.at(i, j).x, g.at(i, j).y);
            if ((i == 0 || j == 0 || i == g.nx - 1 || j == g.ny - 1) && !(x > 0))
                throw Error("contour_loops: the shape reaches the border of its box");
            g.v[size_t(j * g.nx + i)] = x;
        }
    return g;
}

// The loops of g + shift (per node; none when empty) < 0, inside on the left.
std::vector<std::vector<P2>> trace(const Grid& g, const std::vector<double>& shift, double tolerance) {
    const int64_t nx = g.nx, ny = g.ny;
    auto value = [&](int64_t i, int64_t j) {
        const size_t n = size_t(j * nx + i);
        const double x = g.v[n] + (shift.empty() ? 0 : shift[n]);
        return x == 0 ? 1e-12 : x;  // a zero counts as outside
    };
    // Crossing points, keyed by grid edge: horizontal edges first, then vertical.
    const int64_t horizontal = (nx - 1) * ny;
    auto hid = [&](int64_t i, int64_t j) { return j * (nx - 1) + i; };
    auto vid = [&](int64_t i, int64_t j) { return horizontal + j * nx + i; };
    auto point = [&](int64_t e) {
        int64_t i0, j0, i1, j1;
        if (e < horizontal) i0 = e % (nx - 1), j0 = e / (nx - 1), i1 = i0 + 1, j1 = j0;
        else i0 = (e - horizontal) % nx, j0 = (e - horizontal) / nx, i1 = i0, j1 = j0 + 1;
        const double a = value(i0, j0), b = value(i1, j1), t = a / (a - b);
        return P2{g.lo.x + (double(i0) + t * double(i1 - i0)) * g.step, g.lo.y + (double(j0) + t * double(j1 - j0)) * g.step};
    };
    // Each cell's segments run from where its counter-clockwise boundary walk
    // leaves the inside to where it re-enters, so the inside stays on the left.
    std::unordered_map<int64_t, int64_t> next;
    for (int64_t j = 0; j + 1 < ny; ++j)
        for (int64_t i = 0; i + 1 < nx; ++i) {
            const double c[4] = {value(i, j), value(i + 1, j), value(i + 1, j + 1), value(i, j + 1)};
            const int64_t e[4] = {hid(i, j), vid(i + 1, j), hid(i, j + 1), vid(i, j)};
            bool in[4], exit[4], entry[4];
            for (int k = 0; k < 4; ++k) in[k] = c[k] < 0;
            for (int k = 0; k < 4; ++k) exit[k] = in[k] && !in[(k + 1) % 4], entry[k] = !in[k] && in[(k + 1) % 4];
            const bool joined = c[0] + c[1] + c[2] + c[3] < 0;  // a saddle's two insides meet in the middle
            for (int k = 0; k < 4; ++k) {
                if (!exit[k]) continue;
                for (int s = 1; s < 4; ++s) {
                    const int m = joined ? (k + s) % 4 : (k + 4 - s) % 4;
                    if (entry[m]) {
                        next[e[k]] = e[m];
                        break;
                    }
                }
            }
        }
    std::vector<std::vector<P2>> loops;
    while (!next.empty()) {
        const int64_t start = next.begin()->first;
        std::vector<P2> loop;
        for (int64_t e = start;;) {
            loop.push_back(point(e));
            auto it = next.find(e);
            if (it == next.end()) throw Error("contour_loops: an open contour");
            e = it->second;
            next.erase(it);
            if (e == start) break;
        }
        if (loop.size() < 3) continue;
        loop = simplify_loop(loop, tolerance);
        if (loop.size() >= 3) loops.push_back(std::move(loop));  // a touch of zero at a node can leave a sliver
    }
    return loops;
}

}  // namespace

std::vector<std::vector<P2>> contour_loops(const std::function<double(double, double)>& f, P2 lo, P2 hi, double step,
                                           double tolerance) {
    return trace(sample_grid(f, lo, hi, step), {}, tolerance);
}

std::vector<P2> rounded(const std::vector<P2>& pl, const std::vector<double>& radius, int segments) {
    std::vector<P2> out{pl.front()};
    auto push = [&](P2 p) {
        if (norm(p.x - out.back().x, p.y - out.back().y) > 1e-9) out.push_back(p);
    };
    for (size_t i = 1; i + 1 < pl.size(); ++i) {
        const P2 a = pl[i - 1], b = pl[i], c = pl[i + 1];
        const double la = norm(a.x - b.x, a.y - b.y), lc = norm(c.x - b.x, c.y - b.y);
        const P2 u1{(a.x - b.x) / la, (a.y - b.y) / la}, u2{(c.x - b.x) / lc, (c.y - b.y) / lc};
        const double ang = std::acos(std::clamp(u1.x * u2.x + u1.y * u2.y, -1.0, 1.0));
        double r = i < radius.size() ? radius[i] : 0;
        if (r <= 0 || ang > M_PI - 1e-6) {
            push(b);
            continue;
        }
        double t = r / std::tan(ang / 2);
        if (t > 0.5 * std::min(la, lc)) t = 0.5 * std::min(la, lc), r = t * std::tan(ang / 2);
        const double bl = norm(u1.x + u2.x, u1.y + u2.y), h = r / std::sin(ang / 2);
        const P2 o{b.x + (u1.x + u2.x) / bl * h, b.y + (u1.y + u2.y) / bl * h};
        const double a1 = std::atan2(b.y + u1.y * t - o.y, b.x + u1.x * t - o.x);
        double d = std::atan2(b.y + u2.y * t - o.y, b.x + u2.x * t - o.x) - a1;
        while (d > M_PI) d -= 2 * M_PI;
        while (d <= -M_PI) d += 2 * M_PI;
        for (int s = 0; s <= segments; ++s) {
            const double t = a1 + d * s / segments;
            push({o.x + r * std::cos(t), o.y + r * std::sin(t)});
        }
    }
    push(pl.back());
    return out;
}

std::vector<uint32_t> triangulate_with_holes(const std::vector<P2>& outer, const std::vector<std::vector<P2>>& holes) {
    std::vector<P2> pts = outer;
    std::vector<uint32_t> poly(outer.size());
    for (size_t i = 0; i < outer.size(); ++i) poly[i] = uint32_t(area2(outer) > 0 ? i : outer.size() - 1 - i);
    std::vector<std::vector<uint32_t>> rings;  // each hole clockwise
    for (const auto& h : holes) {
        const uint32_t base = uint32_t(pts.size());
        pts.insert(pts.end(), h.begin(), h.end());
        std::vector<uint32_t> r(h.size());
        for (size_t i = 0; i < h.size(); ++i) r[i] = base + uint32_t(area2(h) < 0 ? i : h.size() - 1 - i);
        rings.push_back(r);
    }
    auto rightmost = [&](const std::vector<uint32_t>& r) {
        size_t best = 0;
        for (size_t i = 1; i < r.size(); ++i)
            if (pts[r[i]].x > pts[r[best]].x) best = i;
        return best;
    };
    // Holes from the rightmost in, each bridged to the nearest outline corner it sees.
    std::sort(rings.begin(), rings.end(), [&](const auto& a, const auto& b) {
        return pts[a[rightmost(a)]].x > pts[b[rightmost(b)]].x;
    });
    for (size_t h = 0; h < rings.size(); ++h) {
        const size_t im = rightmost(rings[h]);
        const P2 m = pts[rings[h][im]];
        auto clear = [&](P2 p) {
            auto clear_of = [&](const std::vector<uint32_t>& r) {
                for (size_t i = 0; i < r.size(); ++i) {
                    const P2 a = pts[r[i]], c = pts[r[(i + 1) % r.size()]];
                    if (same(a, m) || same(c, m) || same(a, p) || same(c, p)) continue;
                    if (crosses(m, p, a, c)) return false;
                }
                return true;
            };
            if (!clear_of(poly)) return false;
            for (size_t g = h; g < rings.size(); ++g)
                if (!clear_of(rings[g])) return false;
            return true;
        };
        std::vector<size_t> order(poly.size());
        for (size_t i = 0; i < order.size(); ++i) order[i] = i;
        auto dist = [&](size_t i) { return norm(pts[poly[i]].x - m.x, pts[poly[i]].y - m.y); };
        std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return dist(a) < dist(b); });
        size_t at = poly.size();
        for (size_t i : order) {
            const size_t n = poly.size();
            const P2 p = pts[poly[i]];
            if (into_corner(pts[poly[(i + n - 1) % n]], p, pts[poly[(i + 1) % n]], {m.x - p.x, m.y - p.y}) && clear(p)) {
                at = i;
                break;
            }
        }
        if (at == poly.size()) throw Error("triangulate_with_holes: a hole sees no corner of the outline");
        std::vector<uint32_t> merged(poly.begin(), poly.begin() + long(at) + 1);
        const auto& r = rings[h];
        for (size_t i = 0; i <= r.size(); ++i) merged.push_back(r[(im + i) % r.size()]);
        merged.insert(merged.end(), poly.begin() + long(at), poly.end());
        poly = std::move(merged);
    }
    std::vector<P2> flat;
    for (uint32_t i : poly) flat.push_back(pts[i]);
    std::vector<uint32_t> tri = ear_clip(flat);
    for (uint32_t& t : tri) t = poly[t];
    return tri;
}

namespace {

// Drops repeated and exactly collinear points (resampling then spaces the
// points evenly).
std::vector<P2> cleaned(const std::vector<P2>& loop) {
    std::vector<P2> out;
    for (const P2& p : loop)
        if (out.empty() || !same(out.back(), p)) out.push_back(p);
    while (out.size() > 1 && same(out.front(), out.back())) out.pop_back();
    for (bool changed = true; changed && out.size() > 3;) {
        changed = false;
        for (size_t i = 0; i < out.size() && out.size() > 3; ++i) {
            const P2 a = out[(i + out.size() - 1) % out.size()], b = out[i], c = out[(i + 1) % out.size()];
            if (std::abs(cross2(a, b, c)) <= 1e-12 * norm(b.x - a.x, b.y - a.y) * norm(c.x - b.x, c.y - b.y)) {
                out.erase(out.begin() + long(i));
                changed = true;
            }
        }
    }
    return out;
}

bool inside(const std::vector<P2>& poly, P2 p) {
    bool in = false;
    for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
        if ((poly[i].y > p.y) != (poly[j].y > p.y) &&
            p.x < poly[j].x + (poly[i].x - poly[j].x) * (p.y - poly[j].y) / (poly[i].y - poly[j].y))
            in = !in;
    return in;
}

// The outline's points carried onto an inset loop of it (a rim ring): each
// to the nearest point of the loop, in order. Where the inset pinches off a
// feature narrower than itself, later points would fall back along the loop;
// they stay where the last one landed instead (and the builder welds them), so
// the ring never folds over.
std::vector<P2> follow(const std::vector<P2>& outline, const std::vector<std::vector<P2>>& level) {
    const bool ccw = area2(outline) > 0;
    auto seg_nearest = [](const std::vector<P2>& r, size_t j, P2 p, double& t) {
        const P2 a = r[j], b = r[(j + 1) % r.size()];
        const double ex = b.x - a.x, ey = b.y - a.y, l2 = ex * ex + ey * ey;
        t = l2 > 0 ? std::clamp(((p.x - a.x) * ex + (p.y - a.y) * ey) / l2, 0.0, 1.0) : 0;
        return norm(a.x + t * ex - p.x, a.y + t * ey - p.y);
    };
    const std::vector<P2>* ring = nullptr;
    double best = 1e300;
    for (const auto& r : level) {
        if ((area2(r) > 0) != ccw) continue;
        for (size_t j = 0; j < r.size(); ++j) {
            double t;
            const double d = seg_nearest(r, j, outline[0], t);
            if (d < best) best = d, ring = &r;
        }
    }
    if (!ring) throw Error("sheet: the rim's inset lost a loop (a part narrower than twice its edge radius?)");
    const std::vector<P2>& r = *ring;
    const size_t m = r.size();
    std::vector<double> cum(m + 1, 0);
    for (size_t j = 0; j < m; ++j) cum[j + 1] = cum[j] + norm(r[(j + 1) % m].x - r[j].x, r[(j + 1) % m].y - r[j].y);
    const double total = cum[m];
    auto where = [&](double u) {
        u = std::fmod(u, total);
        if (u < 0) u += total;
        const size_t j = size_t(std::upper_bound(cum.begin(), cum.end(), u) - cum.begin()) - 1;
        const double t = cum[j + 1] > cum[j] ? (u - cum[j]) / (cum[j + 1] - cum[j]) : 0;
        const P2 a = r[j % m], b = r[(j + 1) % m];
        return P2{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
    };
    auto nearest = [&](P2 p, size_t from, size_t span, size_t& seg) {
        double bd = 1e300, bu = 0;
        for (size_t k = 0; k < span; ++k) {
            const size_t j = (from + k) % m;
            double t;
            const double d = seg_nearest(r, j, p, t);
            if (d < bd) bd = d, bu = cum[j] + t * (cum[j + 1] - cum[j]), seg = j;
        }
        return bu;
    };
    size_t seg = 0;
    double u = nearest(outline[0], 0, m, seg), walked = 0;
    std::vector<P2> out{where(u)};
    for (size_t i = 1; i < outline.size(); ++i) {
        const double v = nearest(outline[i], (seg + m - 8) % m, std::min(m, size_t(160)), seg);
        double step = std::fmod(v - u + 1.5 * total, total) - 0.5 * total;
        if (step < 0) step = 0;  // never back along the ring
        u += step, walked += step;
        out.push_back(where(u));
    }
    if (walked > 1.02 * total) throw Error("sheet: a rim ring went round more than once");
    return out;
}

// Directed edge (a << 32 | b) -> triangle: open addressing, linear probing.
// Several times faster than std::unordered_map for the flips' many small
// lookups, inserts and erases.
class EdgeMap {
public:
    explicit EdgeMap(size_t expected) {
        size_t cap = 16;
        while (cap < 2 * expected) cap *= 2;
        keys_.assign(cap, kEmpty);
        vals_.resize(cap);
    }
    const uint32_t* find(uint64_t k) const {
        for (size_t i = slot(k);; i = (i + 1) & (keys_.size() - 1)) {
            if (keys_[i] == k) return &vals_[i];
            if (keys_[i] == kEmpty) return nullptr;
        }
    }
    void put(uint64_t k, uint32_t v) {
        if (2 * (used_ + 1) > keys_.size()) grow();
        size_t at = keys_.size();
        for (size_t i = slot(k);; i = (i + 1) & (keys_.size() - 1)) {
            if (keys_[i] == k) {
                vals_[i] = v;
                return;
            }
            if (keys_[i] == kGone && at == keys_.size()) at = i;
            if (keys_[i] == kEmpty) {
                if (at == keys_.size()) at = i, ++used_;
                break;
            }
        }
        keys_[at] = k, vals_[at] = v;
    }
    void erase(uint64_t k) {
        for (size_t i = slot(k);; i = (i + 1) & (keys_.size() - 1)) {
            if (keys_[i] == kEmpty) return;
            if (keys_[i] == k) {
                keys_[i] = kGone;
                return;
            }
        }
    }
    template <class F>
    void each(F f) const {
        for (size_t i = 0; i < keys_.size(); ++i)
            if (keys_[i] != kEmpty && keys_[i] != kGone) f(keys_[i], vals_[i]);
    }

private:
    static constexpr uint64_t kEmpty = ~uint64_t(0), kGone = ~uint64_t(0) - 1;
    size_t slot(uint64_t k) const { return size_t((k * 0x9E3779B97F4A7C15ull) >> 20) & (keys_.size() - 1); }
    void grow() {
        std::vector<uint64_t> keys = std::move(keys_);
        std::vector<uint32_t> vals = std::move(vals_);
        keys_.assign(keys.size() * 2, kEmpty);
        vals_.assign(keys.size() * 2, 0);
        used_ = 0;
        for (size_t i = 0; i < keys.size(); ++i)
            if (keys[i] != kEmpty && keys[i] != kGone) put(keys[i], vals[i]);
    }
    std::vector<uint64_t> keys_;
    std::vector<uint32_t> vals_;
    size_t used_ = 0;  // slots ever filled (tombstones included) since the last growth
};

// The flat faces of a mesh (triangles with all corners at one z) as a
// constrained Delaunay triangulation: Lawson flips of an edge whose two
// triangles lie in one plane, when the fourth corner falls inside the other
// three's circumcircle; points inserted into a face; long edges split. Edges
// where a face meets the rim are never flipped or split, so the outline stays.
class Flats {
public:
    explicit Flats(io::TriangleMesh& m) : m_(m), rim_(m.vertex_count(), false), owner_(6 * m.triangle_count()) {
        for (uint32_t t = 0; t < m.triangle_count(); ++t) {
            if (!flat(t, z(tri(t, 0))))
                for (int k = 0; k < 3; ++k) rim_[tri(t, k)] = true;
            for (int k = 0; k < 3; ++k) {
                owner_.put(key(tri(t, k), tri(t, k + 1)), t);
                todo_.push_back(key(tri(t, k), tri(t, k + 1)));
            }
        }
    }

    void legalize() {
        while (!todo_.empty()) {
            const uint64_t e = todo_.back();
            todo_.pop_back();
            flip(uint32_t(e >> 32), uint32_t(e & 0xffffffffu));
        }
    }

    // Splits the face triangle holding (x, y) in the plane z into three, then
    // legalizes; `hint` is where the search starts and ends.
    void insert(double x0, double y0, float h, uint32_t& hint) {
        const double x = float(x0), y = float(y0);  // as stored, so the tests below see what the mesh will
        const uint32_t t = locate({x, y}, h, hint);
        if (t == kNone) return;
        hint = t;
        // Within 1 um of an edge (lattice points often fall on an edge between
        // two others): split the edge there instead; at a corner: drop it.
        for (int k = 0; k < 3; ++k) {
            const P2 e = p2(tri(t, k)), f = p2(tri(t, k + 1));
            const double len = norm(f.x - e.x, f.y - e.y), along = ((x - e.x) * (f.x - e.x) + (y - e.y) * (f.y - e.y)) / (len * len);
            if (std::abs(cross2(e, f, {x, y})) > 1e-3 * len) continue;
            const uint32_t* twin = owner_.find(key(tri(t, k + 1), tri(t, k)));
            if (twin && flat(*twin, h) && along * len > 1e-3 && (1 - along) * len > 1e-3)
                split(tri(t, k), tri(t, k + 1), {float(e.x + along * (f.x - e.x)), float(e.y + along * (f.y - e.y))}, h);
            return;
        }
        const uint32_t a = tri(t, 0), b = tri(t, 1), c = tri(t, 2), v = add_vertex(x, y, h);
        const uint32_t u = uint32_t(m_.triangle_count()), w = u + 1;
        m_.triangles.insert(m_.triangles.end(), {b, c, v, c, a, v});
        m_.triangles[3 * size_t(t) + 2] = v;
        own({t, u, w});
        todo_.insert(todo_.end(), {key(a, b), key(b, c), key(c, a)});
        legalize();
    }

    // Splits, at their midpoints, the edges between two triangles of the plane z
    // that are longer than limit(midpoint), and the halves in turn, legalizing as it goes.
    void refine(float h, const std::function<double(double, double)>& limit) {
        std::vector<uint64_t> queue;
        owner_.each([&](uint64_t e, uint32_t) { queue.push_back(e); });
        while (!queue.empty()) {
            const uint32_t a = uint32_t(queue.back() >> 32), b = uint32_t(queue.back() & 0xffffffffu);
            queue.pop_back();
            const uint32_t *it = owner_.find(key(a, b)), *jt = owner_.find(key(b, a));
            if (!it || !jt || !flat(*it, h) || !flat(*jt, h)) continue;
            const P2 pa = p2(a), pb = p2(b), mid{(pa.x + pb.x) / 2, (pa.y + pb.y) / 2};
            if (norm(pa.x - pb.x, pa.y - pb.y) <= limit(mid.x, mid.y)) continue;
            const uint32_t c = opposite(*it, a, b), d = opposite(*jt, b, a), v = split(a, b, {float(mid.x), float(mid.y)}, h);
            queue.insert(queue.end(), {key(v, a), key(v, b), key(v, c), key(v, d), key(b, c), key(c, a), key(a, d), key(d, b)});
        }
    }

private:
    static constexpr uint32_t kNone = 0xffffffffu;

    // A new vertex at p on the edge a-b, both of its triangles split in two; legalized.
    uint32_t split(uint32_t a, uint32_t b, P2 p, float h) {
        const uint32_t t = *owner_.find(key(a, b)), u = *owner_.find(key(b, a)), c = opposite(t, a, b), d = opposite(u, b, a);
        const uint32_t v = add_vertex(p.x, p.y, h), t2 = uint32_t(m_.triangle_count()), u2 = t2 + 1;
        disown({t, u});
        set(t, a, v, c), set(u, b, v, d);
        m_.triangles.insert(m_.triangles.end(), {v, b, c, v, a, d});
        own({t, u, t2, u2});
        todo_.insert(todo_.end(), {key(b, c), key(c, a), key(a, d), key(d, b)});
        legalize();
        return v;
    }

    static uint64_t key(uint32_t a, uint32_t b) { return (uint64_t(a) << 32) | b; }
    uint32_t tri(uint32_t t, int k) const { return m_.triangles[3 * size_t(t) + size_t(k % 3)]; }
    P2 p2(uint32_t i) const { return {m_.positions[3 * size_t(i)], m_.positions[3 * size_t(i) + 1]}; }
    float z(uint32_t i) const { return m_.positions[3 * size_t(i) + 2]; }
    bool flat(uint32_t t, float h) const { return z(tri(t, 0)) == h && z(tri(t, 1)) == h && z(tri(t, 2)) == h; }
    uint32_t opposite(uint32_t t, uint32_t a, uint32_t b) const {
        for (int k = 0; k < 3; ++k)
            if (tri(t, k) != a && tri(t, k) != b) return tri(t, k);
        return a;
    }
    uint32_t add_vertex(double x, double y, float h) {
        m_.positions.insert(m_.positions.end(), {float(x), float(y), h});
        rim_.push_back(false);
        return uint32_t(m_.vertex_count() - 1);
    }
    void set(uint32_t t, uint32_t a, uint32_t b, uint32_t c) {
        m_.triangles[3 * size_t(t)] = a, m_.triangles[3 * size_t(t) + 1] = b, m_.triangles[3 * size_t(t) + 2] = c;
    }
    void own(std::initializer_list<uint32_t> ts) {
        for (uint32_t t : ts)
            for (int k = 0; k < 3; ++k) owner_.put(key(tri(t, k), tri(t, k + 1)), t);
    }
    void disown(std::initializer_list<uint32_t> ts) {
        for (uint32_t t : ts)
            for (int k = 0; k < 3; ++k) owner_.erase(key(tri(t, k), tri(t, k + 1)));
    }

    // A straight walk across the face from the hint; where the walk meets the
    // rim (the face need not be convex), every triangle of the plane is tried.
    uint32_t locate(P2 p, float h, uint32_t t) const {
        if (t < m_.triangle_count() && flat(t, h))
            for (int steps = 0; steps < 100000; ++steps) {
                const double s = cross2(p2(tri(t, 0)), p2(tri(t, 1)), p2(tri(t, 2))) > 0 ? 1 : -1;
                int out = -1;
                for (int k = 0; k < 3 && out < 0; ++k)
                    if (s * cross2(p2(tri(t, k)), p2(tri(t, k + 1)), p) < 0) out = k;
                if (out < 0) return t;
                const uint32_t* next = owner_.find(key(tri(t, out + 1), tri(t, out)));
                if (!next || !flat(*next, h)) break;
                t = *next;
            }
        for (uint32_t q = 0; q < m_.triangle_count(); ++q) {
            if (!flat(q, h)) continue;
            const double s = cross2(p2(tri(q, 0)), p2(tri(q, 1)), p2(tri(q, 2))) > 0 ? 1 : -1;
            if (s * cross2(p2(tri(q, 0)), p2(tri(q, 1)), p) > 0 && s * cross2(p2(tri(q, 1)), p2(tri(q, 2)), p) > 0 &&
                s * cross2(p2(tri(q, 2)), p2(tri(q, 0)), p) > 0)
                return q;
        }
        return kNone;
    }

    void flip(uint32_t a, uint32_t b) {
        const uint32_t *it = owner_.find(key(a, b)), *jt = owner_.find(key(b, a));
        if (!it || !jt) return;
        const uint32_t t = *it, u = *jt, c = opposite(t, a, b), d = opposite(u, b, a);
        if (z(a) != z(b) || z(a) != z(c) || z(a) != z(d) || owner_.find(key(c, d)) || owner_.find(key(d, c))) return;
        const P2 pa = p2(a), pb = p2(b), pc = p2(c), pd = p2(d);
        const double s = cross2(pa, pb, pc) > 0 ? 1 : -1;
        const double ax = pa.x - pd.x, ay = pa.y - pd.y, bx = pb.x - pd.x, by = pb.y - pd.y, cx = pc.x - pd.x, cy = pc.y - pd.y;
        const double in = (ax * ax + ay * ay) * (bx * cy - cx * by) - (bx * bx + by * by) * (ax * cy - cx * ay) +
                          (cx * cx + cy * cy) * (ax * by - bx * ay);
        if (s * in <= 1e-9 * (ax * ax + ay * ay + bx * bx + by * by + cx * cx + cy * cy)) return;
        // Not convex; or a new triangle of three outline points nearly flat: points
        // of a straight outline are collinear but for float rounding.
        if (s * cross2(pa, pd, pc) <= 0 || s * cross2(pd, pb, pc) <= 0) return;
        auto sliver = [&](uint32_t i, uint32_t j, uint32_t k) {
            if (!rim_[i] || !rim_[j] || !rim_[k]) return false;
            const P2 e = p2(i), f = p2(j), g = p2(k);
            auto l2 = [](P2 q, P2 r) { return (q.x - r.x) * (q.x - r.x) + (q.y - r.y) * (q.y - r.y); };
            return std::abs(cross2(e, f, g)) <= 1e-3 * std::max({l2(e, f), l2(f, g), l2(g, e)});
        };
        if (sliver(a, d, c) || sliver(d, b, c)) return;
        disown({t, u});
        set(t, a, d, c), set(u, d, b, c);
        own({t, u});
        todo_.insert(todo_.end(), {key(a, d), key(d, b), key(b, c), key(c, a)});
    }

    io::TriangleMesh& m_;
    std::vector<bool> rim_;                          // vertices on the rim (the faces' outline)
    EdgeMap owner_;                                 // directed edge -> triangle
    std::vector<uint64_t> todo_;                    // edges to check for a flip
};

// Points for a face's interior, at most 0.7 max_edge apart (their Delaunay
// edges then shorter than max_edge) and 0.45 max_edge from the rim: square
// lattices of halving spacing, each point taken from the coarsest lattice
// fine enough where it lies.
std::vector<P2> interior_points(const SheetSpec& s, const std::function<double(double, double)>& max_edge) {
    double coarse = 0, fine = 1e30;
    for (double x = s.lo.x; x <= s.hi.x; x += 1)
        for (double y = s.lo.y; y <= s.hi.y; y += 1) coarse = std::max(coarse, max_edge(x, y)), fine = std::min(fine, max_edge(x, y));
    std::vector<P2> out;
    const int levels = int(std::ceil(std::log2(coarse / fine))) + 1;
    for (int k = 0; k < levels; ++k) {
        const double h = 0.7 * coarse / std::pow(2.0, k);
        const int64_t nx = int64_t((s.hi.x - s.lo.x) / h) + 1, ny = int64_t((s.hi.y - s.lo.y) / h) + 1;
        for (int64_t j = 0; j < ny; ++j)
            for (int64_t i = 0; i < nx; ++i) {
                if (k > 0 && i % 2 == 0 && j % 2 == 0) continue;  // a point of the coarser lattice
                const double x = s.lo.x + double(i) * h, y = s.lo.y + double(j) * h, l = max_edge(x, y);
                // Level k serves where 0.7 l lies between its spacing and the next coarser one's.
                if (0.7 * l < h && k + 1 < levels) continue;
                if (k > 0 && 0.7 * l >= 2 * h) continue;
                if (s.shape(x, y) > -(s.edge_radius(x, y) + 0.45 * l)) continue;
                out.push_back({x, y});
            }
    }
    return out;
}

// Ring neighbours that a sharp corner's inset brought within 1 um of each
// other become one point (the builder welds them; their wall triangles drop).
void snap_close(std::vector<P2>& ring) {
    const double eps = 1e-3;
    for (size_t i = 1; i < ring.size(); ++i)
        if (norm(ring[i].x - ring[i - 1].x, ring[i].y - ring[i - 1].y) < eps) ring[i] = ring[i - 1];
    for (size_t i = ring.size(); i-- > 1 && norm(ring[i].x - ring[0].x, ring[i].y - ring[0].y) < eps;) ring[i] = ring[0];
}

// The loop with points added (evenly, along each segment) wherever a segment
// is longer than max_edge at its middle, or where its rim meets the face.
std::vector<P2> resampled(const std::vector<P2>& loop, const SheetSpec& s) {
    std::vector<P2> out;
    for (size_t i = 0; i < loop.size(); ++i) {
        const P2 a = loop[i], b = loop[(i + 1) % loop.size()], m{(a.x + b.x) / 2, (a.y + b.y) / 2};
        // The finer of the spacing wanted here and where the rim meets the face (left is inwards).
        const double len = norm(b.x - a.x, b.y - a.y), r = s.edge_radius(m.x, m.y) / len;
        const double step = std::min(s.max_edge(m.x, m.y), s.max_edge(m.x - r * (b.y - a.y), m.y + r * (b.x - a.x)));
        const int n = int(std::ceil(len / step));
        for (int k = 0; k < n; ++k) out.push_back({a.x + (b.x - a.x) * k / n, a.y + (b.y - a.y) * k / n});
    }
    return out;
}

// The rim's rings, bottom (k = 0) to top (k = K): the outline inset by
// edge_radius * (1 - cos a) for a from -90 to 90 degrees, each traced as its
// own level set of the shape and its points carried over from the outline's.
std::vector<std::vector<std::vector<P2>>> rim_rings(const SheetSpec& s, const Grid& grid,
                                                     const std::vector<std::vector<P2>>& loops, int K, double tolerance) {
    std::vector<double> radius(grid.v.size());
    for (int64_t j = 0; j < grid.ny; ++j)
        for (int64_t i = 0; i < grid.nx; ++i) radius[size_t(j * grid.nx + i)] = s.edge_radius(grid.at(i, j).x, grid.at(i, j).y);
    std::vector<std::vector<std::vector<P2>>> rings(size_t(K) + 1);  // rings[k][loop]
    for (int k = 0; k <= K / 2; ++k) {
        const double f = k == 0 ? 1 : 1 - std::cos(-M_PI / 2 + M_PI * k / K);
        if (f < 1e-9) {
            rings[size_t(k)] = loops;
            continue;
        }
        std::vector<double> shift(radius.size());
        for (size_t n = 0; n < shift.size(); ++n) shift[n] = radius[n] * f;
        const auto level = trace(grid, shift, tolerance);
        for (const auto& l : loops) {
            rings[size_t(k)].push_back(follow(l, level));
            snap_close(rings[size_t(k)].back());
        }
    }
    for (int k = K / 2 + 1; k <= K; ++k) rings[size_t(k)] = rings[size_t(K - k)];  // symmetric top to bottom
    return rings;
}

// The bottom and top faces: for each outline (with the holes inside it, in
// the smallest outline holding them) one triangulation of its inset loop,
// used for both faces. ids[k][loop][i] are the rings' vertices.
void add_faces(Builder& b, const std::vector<std::vector<P2>>& face, const std::vector<std::vector<std::vector<uint32_t>>>& ids) {
    for (size_t o = 0; o < face.size(); ++o) {
        if (area2(face[o]) <= 0) continue;
        std::vector<size_t> members{o};
        for (size_t h = 0; h < face.size(); ++h) {
            if (area2(face[h]) >= 0) continue;
            size_t owner = face.size();
            for (size_t c = 0; c < face.size(); ++c)
                if (area2(face[c]) > 0 && inside(face[c], face[h][0]) && (owner == face.size() || area2(face[c]) < area2(face[owner])))
                    owner = c;
            if (owner == o) members.push_back(h);
        }
        std::vector<std::vector<P2>> holes;
        std::vector<uint32_t> bottom, top;
        std::vector<P2> flat, outline;
        for (size_t m : members) {
            std::vector<P2> loop;  // points merged at a sharp corner count once
            for (size_t i = 0, n = face[m].size(); i < n; ++i) {
                if (same(face[m][i], face[m][(i + n - 1) % n])) continue;
                loop.push_back(face[m][i]);
                bottom.push_back(ids.front()[m][i]);
                top.push_back(ids.back()[m][i]);
            }
            (m == o ? outline : holes.emplace_back()) = loop;
            flat.insert(flat.end(), loop.begin(), loop.end());
        }
        // A bad triangulation (ear clipping through a knot) would fold over, so its area must equal the face's.
        const std::vector<uint32_t> tri = triangulate_with_holes(outline, holes);
        double want = area2(outline), got = 0;
        for (const auto& h : holes) want -= std::abs(area2(h));
        for (size_t t = 0; t < tri.size(); t += 3) got += std::abs(cross2(flat[tri[t]], flat[tri[t + 1]], flat[tri[t + 2]])) / 2;
        if (std::abs(got - want) > 1e-6 * std::abs(want)) throw Error("sheet: an outline or hole crosses itself or another");
        for (size_t t = 0; t < tri.size(); t += 3) {
            b.triangle(bottom[tri[t]], bottom[tri[t + 2]], bottom[tri[t + 1]]);
            b.triangle(top[tri[t]], top[tri[t + 1]], top[tri[t + 2]]);
        }
    }
}

}  // namespace

io::TriangleMesh sheet(const SheetSpec& s) {
    const Grid grid = sample_grid(s.shape, s.lo, s.hi, s.step);
    const double tolerance = 0.004;
    std::vector<std::vector<P2>> loops;
    double rim = 0, finest = 1e30;  // the rim's largest radius, the outline's finest spacing
    for (const auto& l : trace(grid, {}, tolerance)) {
        loops.push_back(resampled(cleaned(l), s));
        for (const P2& p : loops.back()) rim = std::max(rim, s.edge_radius(p.x, p.y)), finest = std::min(finest, s.max_edge(p.x, p.y));
    }
    const double half = s.nominal_thickness / 2;
    // Enough rings that the rim's half ellipse has steps no longer than the outline's.
    const int K = std::max({2, s.edge_segments, int(std::ceil(M_PI * std::sqrt((rim * rim + half * half) / 2) / finest))});
    const auto rings = rim_rings(s, grid, loops, K, tolerance);
    Builder b;
    std::vector<std::vector<std::vector<uint32_t>>> ids(size_t(K) + 1);  // ids[k][loop][i]
    for (int k = 0; k <= K; ++k)
        for (const auto& ring : rings[size_t(k)]) {
            ids[size_t(k)].emplace_back();
            for (const P2& p : ring) ids[size_t(k)].back().push_back(b.vertex(p.x, p.y, half * std::sin(-M_PI / 2 + M_PI * k / K)));
        }
    for (size_t k = 0; k < size_t(K); ++k)
        for (size_t l = 0; l < loops.size(); ++l) {
            const auto &lo = ids[k][l], &hi = ids[k + 1][l];
            for (size_t i = 0, n = lo.size(); i < n; ++i) b.quad(lo[i], lo[(i + 1) % n], hi[(i + 1) % n], hi[i]);
        }
    add_faces(b, rings[0], ids);
    // The faces: a constrained Delaunay triangulation of their outline, then
    // interior points, then long edges split (not a chord along a straight
    // outline: its midpoint would fall on the outline and make a flat triangle).
    io::TriangleMesh m = b.finish();
    Flats faces(m);
    faces.legalize();
    for (int side : {1, -1}) {
        const auto& want = side < 0 && s.max_edge_bottom ? s.max_edge_bottom : s.max_edge;
        const float h = float(side * half);
        uint32_t hint = 0;
        for (const P2& p : interior_points(s, want)) faces.insert(p.x, p.y, h, hint);
        faces.refine(h, [&](double x, double y) { return s.shape(x, y) > -(s.edge_radius(x, y) + 0.02) ? 1e30 : want(x, y); });
    }
    return moved(std::move(m), [&](const P3& p) {
        return P3{p.x, p.y, s.centre(p.x, p.y) + p.z / half * s.thickness(p.x, p.y) / 2};
    });
}

io::TriangleMesh moved(io::TriangleMesh mesh, const std::function<P3(const P3&)>& f) {
    for (size_t i = 0; i < mesh.vertex_count(); ++i) {
        const P3 p = f(vertex(mesh, uint32_t(i)));
        mesh.positions[3 * i] = float(p.x), mesh.positions[3 * i + 1] = float(p.y), mesh.positions[3 * i + 2] = float(p.z);
    }
    io::orient_outward(mesh);
    return mesh;
}

io::TriangleMesh join(const std::vector<io::TriangleMesh>& parts) {
    io::TriangleMesh out;
    for (const auto& p : parts) {
        const uint32_t base = uint32_t(out.vertex_count());
        out.positions.insert(out.positions.end(), p.positions.begin(), p.positions.end());
        for (uint32_t i : p.triangles) out.triangles.push_back(base + i);
    }
    return out;
}

}  // namespace vtloc::sim::mesh
