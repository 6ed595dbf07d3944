#pragma once
// The object as the multi-touch filter sees it (SPEC 6, docs/multitouch.md):
// a dense set of surface points with outward normals (a mesh sampled densely, or
// the user's cloud as it is), the hypothesis samples (a subset about `spacing`
// apart; each with the renderer's tangent t1 of its axis z = -n), the spins, and
// a lookup grid whose cells name the nearest dense point within a band around the
// surface and its nearest counterpart on a face turned the other way (a thin part's
// far side: docs/multitouch.md, "Thin parts"), and each dense point's sample.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/ops/pose_evidence.h"
#include "engine/tensor.h"

namespace vtloc::track {

struct SurfaceOptions {
    int64_t target_hypotheses = 120000;  // samples x spins, about
    int n_spin = 36;                     // 10 degrees apart
    int64_t max_cells = 2000000;         // lookup grid cells at most (8 bytes each)
    double band_mm = 4.0;                // cells farther from the surface hold no point
    double min_voxel_mm = 0.5;
    // Host threads the lookup grid is built on (0: up to 4; the grid is the same on any number).
    int threads = 0;
    // The candidates protocol (SPEC 6; the paper's S^c): hypotheses only at these points
    // [C * 3] (each with the normal of its nearest dense point), spacing 0. Empty: the surface.
    std::vector<float> candidates;
};

struct Surface {
    std::vector<float> dense;     // [D, 6] point, outward unit normal (object units)
    std::vector<float> samples;   // [S, 9] point, normal, t1
    std::vector<float> spins;     // [NS, 2] cos, sin of 2 pi j / NS
    // [nx*ny*nz, 2]: the nearest dense point, and the nearest whose normal opposes the
    // first's (-1: none within the band).
    std::vector<int32_t> cells;
    // [D]: per dense point, the sample nearest its cell's centre on the point's own face
    // (-1: none within the band), where a pose there reads a field.
    std::vector<int32_t> dense_sample;
    std::array<float, 3> origin{};
    float voxel = 1;
    std::array<int32_t, 3> dims{};
    double spacing_mm = 0;        // hypothesis sample spacing
    double diameter = 0;          // largest distance between two dense points (bounding-box bound)
    bool from_mesh = false;
    bool from_candidates = false;  // the candidates protocol: each sample is a candidate contact

    int64_t n_dense() const { return int64_t(dense.size() / 6); }
    int64_t n_samples() const { return int64_t(samples.size() / 9); }
    int n_spin() const { return int(spins.size() / 2); }
    int64_t n_hypotheses() const { return n_samples() * n_spin(); }
    int64_t n_cells() const { return int64_t(dims[0]) * dims[1] * dims[2]; }
    // The GPU holds the dense points as [D, 8] and the samples as [S, 12] (pose_evidence's rows).
    uint64_t device_bytes() const {
        return 4 * (8 * dense.size() / 6 + 12 * samples.size() / 9 + spins.size() + cells.size());
    }
    uint64_t host_bytes() const {
        return 4 * (dense.size() + samples.size() + spins.size() + cells.size() + dense_sample.size());
    }
    // The grid cell holding q (-1 outside): the mirror's lookup (ops::pose::cell_of), so the
    // host and the evidence agree on every cell.
    int64_t cell_of(const float* q) const;
    // These tables as the CPU mirror's grid (engine/ops/pose_evidence.h); it points into them.
    ops::pose::Grid grid() const {
        return {dense.data(), dense_sample.data(), cells.data(), samples.data(), spins.data(), int32_t(n_spin()),
                {origin[0], origin[1], origin[2]}, voxel, dims[0], dims[1], dims[2]};
    }
};

// dense [D, 6]: points and outward normals; from_mesh says whether they were
// sampled from a mesh (dense, exact normals) or are a user's cloud. Throws
// vtloc::Error naming `source` for an empty set, non-finite values, zero normals.
Surface build_surface(const HostTensor& dense, bool from_mesh, const SurfaceOptions& o = {},
                      const std::string& source = "object");

// Per point of pts ([n, stride], a unit normal at 3..5), 1 where some point of the set
// within `reach` may have a normal turned away from its own (a dot product below 1e-4);
// 0 where none can. build_surface's far-face pass skips the 0s (surface.cpp).
std::vector<char> may_oppose(const float* pts, int64_t n, int64_t stride, const Surface& s, double reach);

// The samples near each sample, for the filter's field_slack op (engine/ops/field_slack.cpp):
// [S, kn, 3] rows (s' as a float, squared distance, the spin offset that keeps a pose's
// heading from s to s'), the kn nearest within `radius` whose normal is within 45 degrees
// of s's (another face is another pose), nearest first, -1 rows after the last.
constexpr double kSlackMinCos = 0.7071;
HostTensor slack_neighbours(const Surface& s, int kn, double radius);

// The renderer's tangent t1 of unit axis a (engine/sim/touch_renderer.cpp: from
// the world axis least aligned with a), so spin 0 means the dataset's spin_deg 0.
std::array<double, 3> tangent_of(const std::array<double, 3>& a);

}  // namespace vtloc::track
