#include "engine/sim/mesh_builder.h"

#include <algorithm>
#include <array>
#include <map>
#include <cmath>

#include "base/error.h"

namespace vtloc::sim::mesh {

namespace {

struct V3 {
    double x, y, z;
};
V3 sub(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

V3 position(const io::TriangleMesh& m, uint32_t i) {
    return {m.positions[3 * size_t(i)], m.positions[3 * size_t(i) + 1], m.positions[3 * size_t(i) + 2]};
}

double cross2(P2 o, P2 a, P2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

double polygon_area(const std::vector<P2>& poly) {
    double s = 0;
    for (size_t i = 0, n = poly.size(); i < n; ++i) {
        const P2 &a = poly[i], &b = poly[(i + 1) % n];
        s += a.x * b.y - b.x * a.y;
    }
    return 0.5 * s;
}

// Splits quad a-b-c-d (in order) along the diagonal through the vertex whose
// height deviates most from the quad's mean, so a pyramid apex or a ridge
// crest is a mesh edge rather than being cut off.
void height_quad(Builder& b, const uint32_t q[4], const double h[4]) {
    double mean = 0.25 * (h[0] + h[1] + h[2] + h[3]);
    int best = 0;
    for (int k = 1; k < 4; ++k)
        if (std::abs(h[k] - mean) > std::abs(h[best] - mean) + 1e-12) best = k;
    if (best % 2 == 0)
        b.quad(q[0], q[1], q[2], q[3]);
    else
        b.quad(q[1], q[2], q[3], q[0]);
}

}  // namespace

uint32_t Builder::vertex(double x, double y, double z) {
    m_.positions.insert(m_.positions.end(), {float(x), float(y), float(z)});
    return uint32_t(m_.vertex_count() - 1);
}

void Builder::triangle(uint32_t a, uint32_t b, uint32_t c) {
    if (a == b || b == c || a == c) return;
    V3 pa = position(m_, a), e1 = sub(position(m_, b), pa), e2 = sub(position(m_, c), pa);
    double n = std::sqrt(dot(cross(e1, e2), cross(e1, e2)));
    // Relative test: repeated grid coordinates make exactly flat triangles.
    if (!(n > 1e-9 * std::sqrt(dot(e1, e1) * dot(e2, e2)))) return;
    m_.triangles.insert(m_.triangles.end(), {a, b, c});
}

void Builder::quad(uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
    triangle(a, b, c);
    triangle(a, c, d);
}

void Builder::append(const io::TriangleMesh& other) {
    uint32_t base = uint32_t(m_.vertex_count());
    m_.positions.insert(m_.positions.end(), other.positions.begin(), other.positions.end());
    for (uint32_t i : other.triangles) m_.triangles.push_back(base + i);
}

io::TriangleMesh Builder::finish() {
    // Weld vertices at identical positions (grid steps and poles repeat them)
    // so that every edge of a closed mesh pairs with its reverse.
    std::map<std::array<float, 3>, uint32_t> seen;
    std::vector<uint32_t> remap(m_.vertex_count());
    std::vector<float> welded;
    for (size_t i = 0; i < m_.vertex_count(); ++i) {
        std::array<float, 3> p{m_.positions[3 * i], m_.positions[3 * i + 1], m_.positions[3 * i + 2]};
        auto [it, fresh] = seen.emplace(p, uint32_t(welded.size() / 3));
        if (fresh) welded.insert(welded.end(), p.begin(), p.end());
        remap[i] = it->second;
    }
    std::vector<uint32_t> tris;
    for (size_t t = 0; t < m_.triangle_count(); ++t) {
        uint32_t a = remap[m_.triangles[3 * t]], b = remap[m_.triangles[3 * t + 1]], c = remap[m_.triangles[3 * t + 2]];
        if (a != b && b != c && a != c) tris.insert(tris.end(), {a, b, c});
    }
    m_.positions = std::move(welded);
    m_.triangles = std::move(tris);
    io::orient_outward(m_);
    return std::move(m_);
}

double signed_volume(const io::TriangleMesh& mesh) { return io::signed_volume(mesh); }

std::vector<uint32_t> triangulate_polygon(const std::vector<P2>& poly_in) {
    const size_t n = poly_in.size();
    if (n < 3) throw Error("triangulate_polygon: fewer than 3 points");
    bool ccw = polygon_area(poly_in) > 0;
    std::vector<uint32_t> idx(n);
    for (size_t i = 0; i < n; ++i) idx[i] = uint32_t(ccw ? i : n - 1 - i);
    const auto& p = poly_in;
    std::vector<uint32_t> out;
    out.reserve(3 * (n - 2));
    auto blocked = [&](size_t ia, size_t ib, size_t ic) {
        P2 a = p[idx[ia]], b = p[idx[ib]], c = p[idx[ic]];
        for (size_t k = 0; k < idx.size(); ++k) {
            if (k == ia || k == ib || k == ic) continue;
            P2 q = p[idx[k]];
            bool at_corner = (q.x == a.x && q.y == a.y) || (q.x == b.x && q.y == b.y) || (q.x == c.x && q.y == c.y);
            if (at_corner) continue;
            // Inside or on the edges blocks: a vertex on the new diagonal would leave a spike.
            if (cross2(a, b, q) >= 0 && cross2(b, c, q) >= 0 && cross2(c, a, q) >= 0) return true;
        }
        return false;
    };
    size_t i = 0, misses = 0;
    while (idx.size() > 3) {
        size_t m = idx.size();
        size_t ia = (i + m - 1) % m, ic = (i + 1) % m;
        double turn = cross2(p[idx[ia]], p[idx[i]], p[idx[ic]]);
        // A convex corner with nothing in it is an ear; after a full fruitless
        // pass (float trouble) the corner is clipped anyway so the loop ends.
        if ((turn > 0 && !blocked(ia, i, ic)) || misses > m) {
            out.insert(out.end(), {idx[ia], idx[i], idx[ic]});
            idx.erase(idx.begin() + long(i));
            misses = 0;
            if (i >= idx.size()) i = 0;
        } else {
            ++misses;
            i = (i + 1) % m;
        }
    }
    out.insert(out.end(), {idx[0], idx[1], idx[2]});
    return out;
}

io::TriangleMesh extrude(const std::vector<P2>& outline_in, double z0, double z1) {
    std::vector<P2> outline = outline_in;
    if (polygon_area(outline) < 0) std::reverse(outline.begin(), outline.end());
    const size_t n = outline.size();
    Builder b;
    std::vector<uint32_t> bot(n), top(n);
    for (size_t i = 0; i < n; ++i) bot[i] = b.vertex(outline[i].x, outline[i].y, z0);
    for (size_t i = 0; i < n; ++i) top[i] = b.vertex(outline[i].x, outline[i].y, z1);
    std::vector<uint32_t> tri = triangulate_polygon(outline);
    for (size_t t = 0; t < tri.size(); t += 3) {
        b.triangle(top[tri[t]], top[tri[t + 1]], top[tri[t + 2]]);
        b.triangle(bot[tri[t]], bot[tri[t + 2]], bot[tri[t + 1]]);
    }
    for (size_t i = 0; i < n; ++i) {
        size_t j = (i + 1) % n;
        b.quad(bot[i], bot[j], top[j], top[i]);
    }
    return b.finish();
}

namespace {

// Rings of n vertices (or one pole vertex where r == 0) for each profile
// point, joined ring to ring; `closed` joins the last ring back to the first.
io::TriangleMesh revolve_rings(const std::vector<P2>& profile, int segments, bool closed) {
    const size_t k = profile.size(), n = size_t(segments);
    Builder b;
    std::vector<std::vector<uint32_t>> rings(k);
    for (size_t r = 0; r < k; ++r) {
        if (profile[r].x <= 0) {
            rings[r].assign(n, b.vertex(0, 0, profile[r].y));
            continue;
        }
        for (size_t i = 0; i < n; ++i) {
            double a = 2 * M_PI * double(i) / double(n);
            rings[r].push_back(b.vertex(profile[r].x * std::cos(a), profile[r].x * std::sin(a), profile[r].y));
        }
    }
    for (size_t r = 0; r + (closed ? 0 : 1) < k; ++r) {
        const auto &lo = rings[r], &hi = rings[(r + 1) % k];
        for (size_t i = 0; i < n; ++i) b.quad(lo[i], lo[(i + 1) % n], hi[(i + 1) % n], hi[i]);
    }
    if (!closed) {
        if (profile.front().x > 0) {
            uint32_t c = b.vertex(0, 0, profile.front().y);
            for (size_t i = 0; i < n; ++i) b.triangle(c, rings[0][(i + 1) % n], rings[0][i]);
        }
        if (profile.back().x > 0) {
            uint32_t c = b.vertex(0, 0, profile.back().y);
            for (size_t i = 0; i < n; ++i) b.triangle(c, rings[k - 1][i], rings[k - 1][(i + 1) % n]);
        }
    }
    return b.finish();
}

}  // namespace

io::TriangleMesh revolve(const std::vector<P2>& profile, int segments) {
    return revolve_rings(profile, segments, false);
}

io::TriangleMesh revolve_closed(const std::vector<P2>& profile, int segments) {
    return revolve_rings(profile, segments, true);
}

io::TriangleMesh slab(const std::vector<double>& xs, const std::vector<double>& ys,
                      const std::function<double(size_t, size_t)>& top,
                      const std::function<double(size_t, size_t)>& bottom) {
    const size_t nx = xs.size(), ny = ys.size();
    Builder b;
    std::vector<uint32_t> t(nx * ny), w(nx * ny);
    std::vector<double> ht(nx * ny), hb(nx * ny);
    for (size_t i = 0; i < nx; ++i)
        for (size_t j = 0; j < ny; ++j) {
            ht[i * ny + j] = top(i, j);
            hb[i * ny + j] = bottom(i, j);
            t[i * ny + j] = b.vertex(xs[i], ys[j], ht[i * ny + j]);
            w[i * ny + j] = b.vertex(xs[i], ys[j], hb[i * ny + j]);
        }
    auto at = [&](size_t i, size_t j) { return i * ny + j; };
    for (size_t i = 0; i + 1 < nx; ++i)
        for (size_t j = 0; j + 1 < ny; ++j) {
            size_t c[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
            uint32_t qt[4] = {t[c[0]], t[c[1]], t[c[2]], t[c[3]]};
            double h[4] = {ht[c[0]], ht[c[1]], ht[c[2]], ht[c[3]]};
            height_quad(b, qt, h);
            uint32_t qb[4] = {w[c[0]], w[c[3]], w[c[2]], w[c[1]]};
            double g[4] = {hb[c[0]], hb[c[3]], hb[c[2]], hb[c[1]]};
            height_quad(b, qb, g);
        }
    // Side walls, wound to match the top and bottom grids' boundary edges.
    for (size_t i = 0; i + 1 < nx; ++i) {
        b.quad(w[at(i, 0)], w[at(i + 1, 0)], t[at(i + 1, 0)], t[at(i, 0)]);
        size_t j = ny - 1;
        b.quad(w[at(i + 1, j)], w[at(i, j)], t[at(i, j)], t[at(i + 1, j)]);
    }
    for (size_t j = 0; j + 1 < ny; ++j) {
        b.quad(w[at(0, j + 1)], w[at(0, j)], t[at(0, j)], t[at(0, j + 1)]);
        size_t i = nx - 1;
        b.quad(w[at(i, j)], w[at(i, j + 1)], t[at(i, j + 1)], t[at(i, j)]);
    }
    return b.finish();
}

io::TriangleMesh radial_tube(int n_theta, const std::vector<double>& zs,
                             const std::function<double(size_t, size_t)>& radius) {
    const size_t n = size_t(n_theta), k = zs.size();
    Builder b;
    std::vector<uint32_t> v(n * k);
    std::vector<double> r(n * k);
    for (size_t i = 0; i < n; ++i) {
        double a = 2 * M_PI * double(i) / double(n);
        for (size_t z = 0; z < k; ++z) {
            r[i * k + z] = radius(i, z);
            v[i * k + z] = b.vertex(r[i * k + z] * std::cos(a), r[i * k + z] * std::sin(a), zs[z]);
        }
    }
    for (size_t i = 0; i < n; ++i) {
        size_t i1 = (i + 1) % n;
        for (size_t z = 0; z + 1 < k; ++z) {
            uint32_t q[4] = {v[i * k + z], v[i1 * k + z], v[i1 * k + z + 1], v[i * k + z + 1]};
            double h[4] = {r[i * k + z], r[i1 * k + z], r[i1 * k + z + 1], r[i * k + z + 1]};
            height_quad(b, q, h);
        }
    }
    uint32_t c0 = b.vertex(0, 0, zs.front()), c1 = b.vertex(0, 0, zs.back());
    for (size_t i = 0; i < n; ++i) {
        size_t i1 = (i + 1) % n;
        b.triangle(c0, v[i1 * k], v[i * k]);
        b.triangle(c1, v[i * k + k - 1], v[i1 * k + k - 1]);
    }
    return b.finish();
}

}  // namespace vtloc::sim::mesh
