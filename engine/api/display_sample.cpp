#include "engine/api/display_sample.h"

#include <cmath>
#include <unordered_map>

#include "base/error.h"
#include "engine/cell_key.h"

namespace vtloc::api {

HostTensor display_sample(const io::TriangleMesh& mesh, int64_t n, const std::string& source) {
    const double area = io::surface_area(mesh);
    if (!(area > 0) || n < 1) throw vtloc::Error(source + ": no surface to draw");
    // Random sequential addition saturates at ~0.55 coverage by discs of radius r/2,
    // i.e. n ~ 0.7 A / r^2; 4x candidates gets close to that count.
    const double r = std::sqrt(0.7 * area / double(n)), r2 = r * r;
    HostTensor cand = io::sample_surface(mesh, 4 * n, io::kDefaultSampleSeed + 1, source);
    std::unordered_map<int64_t, std::vector<int64_t>> grid;
    std::vector<float> kept;
    for (int64_t i = 0; i < cand.shape[0]; ++i) {
        const float* p = &cand.data[size_t(i) * 6];
        const int64_t cx = int64_t(std::floor(p[0] / r)), cy = int64_t(std::floor(p[1] / r)),
                      cz = int64_t(std::floor(p[2] / r));
        bool free = true;
        for (int dx = -1; dx <= 1 && free; ++dx)
            for (int dy = -1; dy <= 1 && free; ++dy)
                for (int dz = -1; dz <= 1 && free; ++dz) {
                    auto it = grid.find(cell_key(cx + dx, cy + dy, cz + dz));
                    if (it == grid.end()) continue;
                    for (int64_t j : it->second) {
                        const float* o = &kept[size_t(j) * 6];
                        double d = 0;
                        for (int k = 0; k < 3; ++k) d += (double(p[k]) - o[k]) * (double(p[k]) - o[k]);
                        if (d < r2) {
                            free = false;
                            break;
                        }
                    }
                }
        if (!free) continue;
        grid[cell_key(cx, cy, cz)].push_back(int64_t(kept.size() / 6));
        kept.insert(kept.end(), p, p + 6);
    }
    const int64_t count = int64_t(kept.size() / 6);
    return HostTensor({count, 6}, std::move(kept));
}

}  // namespace vtloc::api
