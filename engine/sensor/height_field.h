#pragma once
// The object's height field seen by the sensor: an orthographic z-buffer of
// the mesh along the sensor axis over a pixel grid, front and back faces
// alike, plus the exact hit of the centre ray. The renderer's, and what
// render-and-compare (SPEC 9) will press.
#include <array>
#include <cstdint>
#include <vector>

#include "engine/io/mesh.h"

namespace vtloc::sensor {

using V3 = std::array<double, 3>;

// Per-mesh data the renderer keeps: positions in double, per-triangle
// bounding spheres for culling, unit face normals (zero when degenerate).
struct MeshCache {
    std::vector<double> pos;       // 3 per vertex
    std::vector<uint32_t> tri;     // 3 per triangle
    std::vector<double> cx, cy, cz, rad;  // bounding sphere per triangle (centroid, max vertex distance)
    std::vector<double> normal;    // 3 per triangle
    size_t triangle_count() const { return rad.size(); }
    // Throws vtloc::Error for out-of-range indices or non-finite coordinates.
    explicit MeshCache(const io::TriangleMesh& mesh);
};

// The sensor's orthonormal axes (x = columns, y = rows, z = into the object)
// and a point on its centre line; depth w is measured along z from it.
struct SensorFrame {
    V3 x{}, y{}, z{}, origin{};
};

// A grid of `rows` x `cols` pixels centred on the centre line: pixel (r, c)
// has its centre at u = (c - (cols-1)/2) * mm_per_px + u0 along x and
// v = (r - (rows-1)/2) * mm_per_px + v0 along y.
struct PixelGrid {
    int rows = 0, cols = 0;
    double mm_per_px = 1;
    double u0 = 0, v0 = 0;  // offset of the grid centre from the centre line, mm
};

struct HeightField {
    std::vector<double> w;        // rows * cols: depth of the first surface along +z; +inf where none
    double vertex_min = 0;        // smallest depth of a mesh vertex inside the grid's rectangle (+inf if none)
    // The centre line (u = v = 0): first hit's depth and triangle, if any.
    bool centre_hit = false;
    double centre_w = 0;
    int64_t centre_tri = -1;
};

HeightField rasterise(const MeshCache& mesh, const SensorFrame& frame, const PixelGrid& grid);

}  // namespace vtloc::sensor
