#pragma once
// The dense surface points binned on a coarse grid, as codebook_render reads them
// (engine/ops/codebook.cpp): bin by bin, each bin's first point and count.
#include <cstdint>
#include <vector>

namespace vtloc::ops::book {

struct BinnedPoints {
    std::vector<float> points;   // [D, 6], bin by bin
    std::vector<int32_t> bins;   // [nx*ny*nz, 2] first, count
    float origin[3] = {0, 0, 0};
    double coarse = 1;
    int64_t dims[3] = {1, 1, 1};
    int64_t max_bin = 1;
    // The bin (x, y, z) holding point p, clamped to the grid; its index (z * ny + y) * nx + x.
    void cell_of(const float* p, int64_t c[3]) const;
    int64_t index_of(const int64_t c[3]) const { return (c[2] * dims[1] + c[1]) * dims[0] + c[0]; }
};
// dense [D, 6]: points and normals. Bins of at least `coarse` mm, at most 64 per axis.
// Throws vtloc::Error for no points or a bin size <= 0.
BinnedPoints bin_points(const std::vector<float>& dense, double coarse);

}  // namespace vtloc::ops::book
