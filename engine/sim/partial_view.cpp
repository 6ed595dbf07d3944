#include "engine/sim/partial_view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

#include <nlohmann/json.hpp>

#include "engine/error.h"
#include "engine/io/splitmix64.h"
#include "engine/sim/height_field.h"

namespace vtloc::sim {

namespace {

using detail::V3;

V3 cross(const V3& a, const V3& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
V3 unit(const V3& a) {
    const double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    return {a[0] / l, a[1] / l, a[2] / l};
}

// Farthest point sampling from row 0, in double: n rows of `pts` (all if fewer).
std::vector<size_t> farthest(const std::vector<V3>& pts, size_t n) {
    std::vector<size_t> pick;
    if (pts.empty()) return pick;
    std::vector<double> d(pts.size(), std::numeric_limits<double>::infinity());
    size_t cur = 0;
    for (size_t k = 0; k < std::min(n, pts.size()); ++k) {
        pick.push_back(cur);
        size_t best = 0;
        for (size_t i = 0; i < pts.size(); ++i) {
            const double dx = pts[i][0] - pts[cur][0], dy = pts[i][1] - pts[cur][1], dz = pts[i][2] - pts[cur][2];
            d[i] = std::min(d[i], dx * dx + dy * dy + dz * dz);
            if (d[i] > d[best]) best = i;
        }
        cur = best;
    }
    return pick;
}

void write_atomic(const std::filesystem::path& path, const std::string& text) {
    const std::filesystem::path tmp = path.string() + ".tmp";
    {
        std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
        f << text;
        if (!f) throw Error(tmp.string() + ": cannot write");
    }
    std::filesystem::rename(tmp, path);
}

}  // namespace

PartialView render_partial_view(const io::TriangleMesh& mesh, uint64_t seed, int n_points, int pixels) {
    if (n_points < 1 || pixels < 8) throw Error("partial view: n_points >= 1 and pixels >= 8 needed");
    const detail::MeshCache m(mesh);
    // The bounding sphere (centre of the box, farthest vertex).
    V3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (size_t i = 0; i < m.pos.size(); ++i) lo[i % 3] = std::min(lo[i % 3], m.pos[i]), hi[i % 3] = std::max(hi[i % 3], m.pos[i]);
    const V3 c{(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2};
    double r = 0;
    for (size_t i = 0; i + 2 < m.pos.size(); i += 3)
        r = std::max(r, std::sqrt(std::pow(m.pos[i] - c[0], 2) + std::pow(m.pos[i + 1] - c[1], 2) + std::pow(m.pos[i + 2] - c[2], 2)));
    if (!(r > 0)) throw Error("partial view: the mesh has no extent");
    io::SplitMix64 rng(seed);
    V3 z;
    do {  // uniform direction: rejection from the cube
        for (double& v : z) v = 2.0 * rng.uniform() - 1.0;
    } while (z[0] * z[0] + z[1] * z[1] + z[2] * z[2] > 1 || z[0] * z[0] + z[1] * z[1] + z[2] * z[2] < 1e-6);
    z = unit(z);
    const V3 x = unit(cross(std::abs(z[0]) < 0.9 ? V3{1, 0, 0} : V3{0, 1, 0}, z)), y = cross(z, x);
    detail::SensorFrame f{x, y, z, {c[0] - 2 * r * z[0], c[1] - 2 * r * z[1], c[2] - 2 * r * z[2]}};
    detail::PixelGrid g{pixels, pixels, 2.0 * r / pixels, 0, 0};
    const detail::HeightField hf = detail::rasterise(m, f, g);
    std::vector<V3> pts;
    for (int row = 0; row < g.rows; ++row)
        for (int col = 0; col < g.cols; ++col) {
            const double w = hf.w[size_t(row) * size_t(g.cols) + size_t(col)];
            if (!std::isfinite(w)) continue;
            const double u = (col - (g.cols - 1) / 2.0) * g.mm_per_px, v = (row - (g.rows - 1) / 2.0) * g.mm_per_px;
            pts.push_back({f.origin[0] + u * x[0] + v * y[0] + w * z[0], f.origin[1] + u * x[1] + v * y[1] + w * z[1],
                           f.origin[2] + u * x[2] + v * y[2] + w * z[2]});
        }
    if (pts.empty()) throw Error("partial view: no pixel sees the object");
    PartialView out;
    out.visible_pixels = int(pts.size());
    out.direction = z;
    out.camera = {c[0] - 20 * r * z[0], c[1] - 20 * r * z[1], c[2] - 20 * r * z[2]};
    const std::vector<size_t> pick = farthest(pts, size_t(n_points));
    out.xyz = HostTensor({int64_t(pick.size()), 3});
    for (size_t k = 0; k < pick.size(); ++k)
        for (int a = 0; a < 3; ++a) out.xyz.data[k * 3 + size_t(a)] = float(pts[pick[k]][size_t(a)]);
    return out;
}

void write_partial_view(const std::filesystem::path& dir, const PartialView& v) {
    std::string rows = "# x y z: one view of the object (vtloc synth --view), object units\n";
    char buf[128];
    for (int64_t i = 0; i < v.xyz.shape[0]; ++i) {
        std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", v.xyz.data[size_t(i * 3)], v.xyz.data[size_t(i * 3 + 1)],
                      v.xyz.data[size_t(i * 3 + 2)]);
        rows += buf;
    }
    write_atomic(dir / "view.xyz", rows);
    nlohmann::json j{{"format", "vtloc-synth-view/1"},
                     {"projection", "orthographic"},
                     {"direction", v.direction},
                     {"camera", v.camera},
                     {"points", v.xyz.shape[0]},
                     {"visible_pixels", v.visible_pixels}};
    write_atomic(dir / "view.json", j.dump(2) + "\n");
}

}  // namespace vtloc::sim
