#include "engine/sim/partial_view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "base/error.h"
#include "engine/io/file_bytes.h"
#include "engine/io/mesh.h"
#include "engine/io/splitmix64.h"
#include "engine/model/cloud_reduce.h"
#include "engine/sensor/height_field.h"

namespace vtloc::sim {

namespace {

using sensor::V3;

V3 cross(const V3& a, const V3& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
V3 unit(const V3& a) {
    const double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    return {a[0] / l, a[1] / l, a[2] / l};
}

}  // namespace

PartialView render_partial_view(const io::TriangleMesh& mesh, uint64_t seed, int n_points, int pixels) {
    if (n_points < 1 || pixels < 8) throw Error("partial view: n_points >= 1 and pixels >= 8 needed");
    const sensor::MeshCache m(mesh);
    // The bounding sphere (centre of the box, farthest vertex).
    const V3 c = io::bounds(mesh).centre();
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
    sensor::SensorFrame f{x, y, z, {c[0] - 2 * r * z[0], c[1] - 2 * r * z[1], c[2] - 2 * r * z[2]}};
    sensor::PixelGrid g{pixels, pixels, 2.0 * r / pixels, 0, 0};
    const sensor::HeightField hf = sensor::rasterise(m, f, g);
    std::vector<float> pts;  // x y z per visible pixel
    for (int row = 0; row < g.rows; ++row)
        for (int col = 0; col < g.cols; ++col) {
            const double w = hf.w[size_t(row) * size_t(g.cols) + size_t(col)];
            if (!std::isfinite(w)) continue;
            const double u = (col - (g.cols - 1) / 2.0) * g.mm_per_px, v = (row - (g.rows - 1) / 2.0) * g.mm_per_px;
            for (size_t a = 0; a < 3; ++a) pts.push_back(float(f.origin[a] + u * x[a] + v * y[a] + w * z[a]));
        }
    if (pts.empty()) throw Error("partial view: no pixel sees the object");
    PartialView out;
    const int64_t visible = int64_t(pts.size() / 3);  // before pts is moved below
    out.visible_pixels = int(visible);
    out.direction = z;
    out.camera = {c[0] - 20 * r * z[0], c[1] - 20 * r * z[1], c[2] - 20 * r * z[2]};
    const HostTensor all({visible, 3}, std::move(pts));
    const std::vector<int64_t> pick = farthest_points(nullptr, all, n_points);  // the fps op's CPU reference
    out.xyz = HostTensor({int64_t(pick.size()), 3});
    for (size_t k = 0; k < pick.size(); ++k)
        std::copy_n(&all.data[size_t(pick[k]) * 3], 3, &out.xyz.data[k * 3]);
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
    io::write_file_atomic((dir / "view.xyz").string(), rows.data(), rows.size());
    nlohmann::json j{{"format", "vtloc-synth-view/1"},
                     {"projection", "orthographic"},
                     {"direction", v.direction},
                     {"camera", v.camera},
                     {"points", v.xyz.shape[0]},
                     {"visible_pixels", v.visible_pixels}};
    const std::string meta = j.dump(2) + "\n";
    io::write_file_atomic((dir / "view.json").string(), meta.data(), meta.size());
}

bool has_partial_view(const std::filesystem::path& dir) {
    return std::filesystem::exists(dir / "view.xyz") && std::filesystem::exists(dir / "view.json");
}

}  // namespace vtloc::sim
