#pragma once
// Triangle meshes: glTF 2.0 (.gltf with its buffers, or .glb) flattened into
// one list of triangles in the object's frame, and area-weighted surface
// sampling that turns a mesh into the model's point cloud (SPEC section 1).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/tensor.h"

namespace vtloc::io {

struct TriangleMesh {
    std::vector<float> positions;   // 3 per vertex, object units, node transforms applied
    std::vector<float> normals;     // empty, or 3 per vertex (unit); (0,0,0) = this vertex has none
    std::vector<uint32_t> triangles;  // 3 vertex indices each; counter-clockwise seen from the front

    size_t vertex_count() const { return positions.size() / 3; }
    size_t triangle_count() const { return triangles.size() / 3; }
};

// Every primitive of mode TRIANGLES (indexed or not) of every mesh instance
// in the default scene (else scene 0, else every root node), with its node's
// world transform applied (normals by the inverse transpose; triangles of
// mirrored nodes re-wound so that counter-clockwise stays the front). Other
// primitive modes (points, lines, strips, fans) are skipped. Coordinates are
// taken as the object's units as they are (no metre conversion). Textures,
// materials, skins and morph targets are ignored. Throws vtloc::Error naming
// the file for a missing/unreadable/malformed file, unsupported accessors,
// out-of-range indices, non-finite coordinates, zero normals (naming the
// vertex), or no triangles at all.
TriangleMesh load_gltf_mesh(const std::string& path);

inline constexpr uint64_t kDefaultSampleSeed = 0;

// N x 6 (xyz, unit normal) by area-weighted surface sampling, deterministic:
// rng = SplitMix64(seed); for each sample, t = uniform() * total area picks
// the first triangle whose running area sum (double, triangle order) exceeds
// t, then u = uniform(), v = uniform() give barycentrics (1 - sqrt(u),
// sqrt(u) (1 - v), sqrt(u) v) over the triangle's vertices (a, b, c). The
// normal is the interpolated vertex normal where all three vertices have
// one (and it is not degenerate), else the face normal (b - a) x (c - a).
// `source` names the mesh in errors (no triangle with non-zero area).
HostTensor sample_surface(const TriangleMesh& mesh, int64_t n, uint64_t seed = kDefaultSampleSeed,
                          const std::string& source = "mesh");

// The mesh's total triangle area (object units squared).
double surface_area(const TriangleMesh& mesh);

// The axis-aligned box of a mesh's vertices (object units; lo > hi where it has none).
struct MeshBounds {
    std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    std::array<double, 3> centre() const { return {(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2}; }
    double largest_side() const;
};
MeshBounds bounds(const TriangleMesh& mesh);

// Signed volume (object units cubed): positive when a closed mesh is wound outward
// (counter-clockwise seen from outside), negative when wound inward.
double signed_volume(const TriangleMesh& mesh);

// Re-winds every triangle of a mesh wound inward (negative signed volume: e.g. an OFF file
// written the other way round), so that face normals point out of the object; vertex
// normals, where the file gives them, stay the file's. Returns whether it re-wound.
bool orient_outward(TriangleMesh& mesh);

// The multi-touch filter's dense sample of a mesh (api::Tracker, vtloc-bench):
// about 4 points per unit^2 (0.5 mm apart in mm), between 20,000 and 300,000
// points (a memory bound), seed kDefaultSampleSeed + 7.
HostTensor tracker_dense_sample(const TriangleMesh& mesh, const std::string& source);

}  // namespace vtloc::io
