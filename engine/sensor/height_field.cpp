// Orthographic z-buffer rasteriser. Per touch, triangles are culled by their
// bounding spheres against the grid rectangle (cheap enough for 100k+
// triangles at tens of touches per second), then rasterised at pixel
// centres. Edge functions are evaluated with the edge's endpoints in a
// canonical order, so the two triangles sharing an edge compute the same
// value bit for bit and every pixel centre on it is covered: no cracks.
#include "engine/sensor/height_field.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "base/error.h"

namespace vtloc::sensor {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct P2 {
    double x, y, w;  // pixel coordinates (column, row) and depth
};

// Edge function of p against the directed edge (a, b), computed with the
// endpoints in lexicographic order and the sign restored, so (a, b) and
// (b, a) give exactly opposite values.
inline double edge(const P2& a, const P2& b, double px, double py) {
    bool swap = (b.x < a.x) || (b.x == a.x && b.y < a.y);
    const P2& s = swap ? b : a;
    const P2& e = swap ? a : b;
    double v = (e.x - s.x) * (py - s.y) - (e.y - s.y) * (px - s.x);
    return swap ? -v : v;
}

}  // namespace

MeshCache::MeshCache(const io::TriangleMesh& mesh) {
    const size_t nv = mesh.vertex_count();
    if (mesh.positions.size() % 3 != 0) throw Error("touch renderer: mesh positions are not a multiple of 3");
    if (mesh.triangles.size() % 3 != 0) throw Error("touch renderer: mesh triangle indices are not a multiple of 3");
    pos.resize(mesh.positions.size());
    for (size_t i = 0; i < pos.size(); ++i) {
        if (!std::isfinite(mesh.positions[i]))
            throw Error("touch renderer: mesh vertex " + std::to_string(i / 3) + " has a non-finite coordinate");
        pos[i] = mesh.positions[i];
    }
    const size_t nt = mesh.triangle_count();
    tri = mesh.triangles;
    cx.resize(nt), cy.resize(nt), cz.resize(nt), rad.resize(nt), normal.resize(nt * 3);
    for (size_t t = 0; t < nt; ++t) {
        const double* p[3];
        for (int k = 0; k < 3; ++k) {
            uint32_t id = tri[t * 3 + k];
            if (id >= nv)
                throw Error("touch renderer: triangle " + std::to_string(t) + " has vertex index " + std::to_string(id) +
                            " >= " + std::to_string(nv) + " vertices");
            p[k] = &pos[size_t(id) * 3];
        }
        double c[3];
        for (int d = 0; d < 3; ++d) c[d] = (p[0][d] + p[1][d] + p[2][d]) / 3;
        double r2 = 0;
        for (int k = 0; k < 3; ++k) {
            double dx = p[k][0] - c[0], dy = p[k][1] - c[1], dz = p[k][2] - c[2];
            r2 = std::max(r2, dx * dx + dy * dy + dz * dz);
        }
        cx[t] = c[0], cy[t] = c[1], cz[t] = c[2], rad[t] = std::sqrt(r2) * (1 + 1e-9) + 1e-12;
        double e1[3], e2[3];
        for (int d = 0; d < 3; ++d) e1[d] = p[1][d] - p[0][d], e2[d] = p[2][d] - p[0][d];
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int d = 0; d < 3; ++d) normal[t * 3 + d] = len > 0 ? n[d] / len : 0;
    }
}

HeightField rasterise(const MeshCache& m, const SensorFrame& f, const PixelGrid& g) {
    HeightField hf;
    hf.w.assign(size_t(g.rows) * g.cols, kInf);
    hf.vertex_min = kInf;
    const double inv = 1.0 / g.mm_per_px;
    const double ccol = (g.cols - 1) * 0.5 - g.u0 * inv, crow = (g.rows - 1) * 0.5 - g.v0 * inv;
    // Grid rectangle in sensor mm (pixel centres), relative to the centre line.
    const double umin = -ccol * g.mm_per_px, umax = (g.cols - 1 - ccol) * g.mm_per_px;
    const double vmin = -crow * g.mm_per_px, vmax = (g.rows - 1 - crow) * g.mm_per_px;
    const V3 &X = f.x, &Y = f.y, &Z = f.z, &O = f.origin;
    const double ou = O[0] * X[0] + O[1] * X[1] + O[2] * X[2];
    const double ov = O[0] * Y[0] + O[1] * Y[1] + O[2] * Y[2];
    const double ow = O[0] * Z[0] + O[1] * Z[1] + O[2] * Z[2];

    auto project = [&](uint32_t id) {
        const double* p = &m.pos[size_t(id) * 3];
        double u = p[0] * X[0] + p[1] * X[1] + p[2] * X[2] - ou;
        double v = p[0] * Y[0] + p[1] * Y[1] + p[2] * Y[2] - ov;
        double w = p[0] * Z[0] + p[1] * Z[1] + p[2] * Z[2] - ow;
        return P2{u * inv + ccol, v * inv + crow, w};
    };

    const size_t nt = m.triangle_count();
    for (size_t t = 0; t < nt; ++t) {
        // Cull: bounding sphere against the grid rectangle, in the sensor plane.
        const double r = m.rad[t];
        const double u = m.cx[t] * X[0] + m.cy[t] * X[1] + m.cz[t] * X[2] - ou;
        if (u + r < umin || u - r > umax) continue;
        const double v = m.cx[t] * Y[0] + m.cy[t] * Y[1] + m.cz[t] * Y[2] - ov;
        if (v + r < vmin || v - r > vmax) continue;

        const uint32_t* id = &m.tri[t * 3];
        const P2 a = project(id[0]), b = project(id[1]), c = project(id[2]);
        for (const P2* p : {&a, &b, &c})
            if (p->x >= -0.5 && p->x <= g.cols - 0.5 && p->y >= -0.5 && p->y <= g.rows - 0.5)
                hf.vertex_min = std::min(hf.vertex_min, p->w);
        const double area = edge(a, b, c.x, c.y);
        if (area == 0 || !std::isfinite(area)) continue;  // seen edge-on: its neighbours cover it
        const double sgn = area > 0 ? 1.0 : -1.0;

        // The centre line, exactly (it need not fall on a pixel centre).
        {
            double ea = edge(b, c, ccol, crow) * sgn, eb = edge(c, a, ccol, crow) * sgn, ec = edge(a, b, ccol, crow) * sgn;
            if (ea >= 0 && eb >= 0 && ec >= 0) {
                double s = ea + eb + ec;
                double w = (ea * a.w + eb * b.w + ec * c.w) / s;
                if (!hf.centre_hit || w < hf.centre_w) hf.centre_hit = true, hf.centre_w = w, hf.centre_tri = int64_t(t);
            }
        }

        // Clamped in double first: far-away vertices must not overflow int.
        auto lo = [](double v, int n) { return int(std::ceil(std::clamp(v, -1.0, double(n)))); };
        auto hi = [](double v, int n) { return int(std::floor(std::clamp(v, -1.0, double(n)))); };
        const int c0 = std::max(0, lo(std::min({a.x, b.x, c.x}), g.cols));
        const int c1 = std::min(g.cols - 1, hi(std::max({a.x, b.x, c.x}), g.cols));
        const int r0 = std::max(0, lo(std::min({a.y, b.y, c.y}), g.rows));
        const int r1 = std::min(g.rows - 1, hi(std::max({a.y, b.y, c.y}), g.rows));
        if (c0 > c1 || r0 > r1) continue;
        for (int row = r0; row <= r1; ++row) {
            double* out = &hf.w[size_t(row) * g.cols];
            for (int col = c0; col <= c1; ++col) {
                double ea = edge(b, c, col, row) * sgn;
                if (ea < 0) continue;
                double eb = edge(c, a, col, row) * sgn;
                if (eb < 0) continue;
                double ec = edge(a, b, col, row) * sgn;
                if (ec < 0) continue;
                double s = ea + eb + ec;
                double w = (ea * a.w + eb * b.w + ec * c.w) / s;
                if (w < out[col]) out[col] = w;
            }
        }
    }
    return hf;
}

}  // namespace vtloc::sensor
