#include "engine/ops/codebook_bins.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"

namespace vtloc::ops::book {

void BinnedPoints::cell_of(const float* p, int64_t c[3]) const {
    const float inv = float(1.0 / coarse);
    for (int k = 0; k < 3; ++k) c[k] = std::clamp<int64_t>(int64_t(std::floor((p[k] - origin[k]) * inv)), 0, dims[k] - 1);
}

BinnedPoints bin_points(const std::vector<float>& dense, double coarse) {
    const int64_t D = int64_t(dense.size() / 6);
    if (D == 0 || dense.size() % 6) throw Error("codebook: no surface points to render");
    if (!(coarse > 0)) throw Error("codebook: the bin size must be positive");
    BinnedPoints b;
    float hi[3];
    for (int k = 0; k < 3; ++k) b.origin[k] = hi[k] = dense[size_t(k)];
    for (int64_t i = 0; i < D; ++i)
        for (int k = 0; k < 3; ++k) b.origin[k] = std::min(b.origin[k], dense[size_t(6 * i + k)]), hi[k] = std::max(hi[k], dense[size_t(6 * i + k)]);
    // At most 64 bins per axis: a larger object gets larger bins (each sample reads 27).
    b.coarse = std::max(coarse, double(std::max({hi[0] - b.origin[0], hi[1] - b.origin[1], hi[2] - b.origin[2]})) / 64.0);
    const float inv = float(1.0 / b.coarse);
    for (int k = 0; k < 3; ++k) b.dims[k] = std::clamp<int64_t>(int64_t(std::floor((hi[k] - b.origin[k]) * inv)) + 1, 1, 64);
    auto bin_of = [&](const float* p) {
        int64_t c[3];
        b.cell_of(p, c);
        return b.index_of(c);
    };
    const int64_t NB = b.dims[0] * b.dims[1] * b.dims[2];
    std::vector<int32_t> count(size_t(NB), 0), first(size_t(NB) + 1, 0);
    for (int64_t i = 0; i < D; ++i) ++count[size_t(bin_of(&dense[size_t(6 * i)]))];
    for (int64_t c = 0; c < NB; ++c) first[size_t(c + 1)] = first[size_t(c)] + count[size_t(c)];
    b.points.resize(dense.size());
    std::vector<int32_t> at(first.begin(), first.end() - 1);
    for (int64_t i = 0; i < D; ++i) {
        const int32_t k = at[size_t(bin_of(&dense[size_t(6 * i)]))]++;
        std::copy(&dense[size_t(6 * i)], &dense[size_t(6 * i + 6)], &b.points[size_t(6 * k)]);
    }
    b.bins.resize(size_t(2 * NB));
    for (int64_t c = 0; c < NB; ++c) {
        b.bins[size_t(2 * c)] = first[size_t(c)], b.bins[size_t(2 * c + 1)] = count[size_t(c)];
        b.max_bin = std::max<int64_t>(b.max_bin, count[size_t(c)]);
    }
    return b;
}

}  // namespace vtloc::ops::book
