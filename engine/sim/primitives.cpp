// Icosphere by midpoint subdivision (shared midpoints, so the mesh stays
// welded and crack-free) and a gridded rectangle.
#include "engine/sim/primitives.h"

#include <cmath>
#include <algorithm>
#include <map>
#include <string>
#include <utility>

#include "base/error.h"

namespace vtloc::sim {

io::TriangleMesh make_icosphere(double radius, int subdivisions, const std::array<double, 3>& centre) {
    if (!(radius > 0) || !std::isfinite(radius)) throw Error("make_icosphere: radius must be > 0");
    if (subdivisions < 0 || subdivisions > 8) throw Error("make_icosphere: subdivisions must be 0..8");
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<std::array<double, 3>> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                            {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    std::vector<std::array<uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                              {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                              {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                              {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    auto unit = [](std::array<double, 3> a) {
        double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        return std::array<double, 3>{a[0] / n, a[1] / n, a[2] / n};
    };
    for (auto& p : v) p = unit(p);
    for (int s = 0; s < subdivisions; ++s) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            v.push_back(unit({v[a][0] + v[b][0], v[a][1] + v[b][1], v[a][2] + v[b][2]}));
            uint32_t id = uint32_t(v.size() - 1);
            mid.emplace(key, id);
            return id;
        };
        std::vector<std::array<uint32_t, 3>> g;
        g.reserve(f.size() * 4);
        for (auto& tri : f) {
            uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
            g.push_back({tri[0], a, c});
            g.push_back({tri[1], b, a});
            g.push_back({tri[2], c, b});
            g.push_back({a, b, c});
        }
        f = std::move(g);
    }
    io::TriangleMesh m;
    m.positions.reserve(v.size() * 3);
    m.normals.reserve(v.size() * 3);
    for (auto& p : v)
        for (int k = 0; k < 3; ++k) {
            m.positions.push_back(float(centre[k] + radius * p[k]));
            m.normals.push_back(float(p[k]));
        }
    for (auto& tri : f) m.triangles.insert(m.triangles.end(), tri.begin(), tri.end());
    return m;
}

io::TriangleMesh make_plane(double size_x, double size_y, int nx, int ny) {
    if (!(size_x > 0) || !(size_y > 0) || !std::isfinite(size_x) || !std::isfinite(size_y))
        throw Error("make_plane: sizes must be > 0");
    if (nx < 1 || ny < 1 || nx > 4096 || ny > 4096) throw Error("make_plane: cells must be 1..4096 a side");
    io::TriangleMesh m;
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) {
            m.positions.push_back(float(size_x * (double(i) / nx - 0.5)));
            m.positions.push_back(float(size_y * (double(j) / ny - 0.5)));
            m.positions.push_back(0.0f);
            m.normals.insert(m.normals.end(), {0.0f, 0.0f, 1.0f});
        }
    auto id = [&](int i, int j) { return uint32_t(j * (nx + 1) + i); };
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            m.triangles.insert(m.triangles.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            m.triangles.insert(m.triangles.end(), {id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    return m;
}

}  // namespace vtloc::sim
