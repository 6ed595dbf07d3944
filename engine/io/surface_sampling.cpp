// Area-weighted surface sampling (SPEC section 1). The draw order is part of
// the contract (see mesh.h) so that another implementation can reproduce it.
#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/io/mesh.h"
#include "engine/io/splitmix64.h"

namespace vtloc::io {

namespace {

struct V3 {
    double x, y, z;
};
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
double norm(V3 a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }

// Corner k of triangle t, in double.
V3 corner(const TriangleMesh& mesh, size_t t, size_t k) {
    const float* q = &mesh.positions[3 * size_t(mesh.triangles[3 * t + k])];
    return {q[0], q[1], q[2]};
}

}  // namespace

HostTensor sample_surface(const TriangleMesh& mesh, int64_t n, uint64_t seed, const std::string& source) {
    if (n < 0) throw Error(source + ": cannot sample a negative number of points");
    const size_t nt = mesh.triangle_count();
    for (uint32_t id : mesh.triangles)
        if (id >= mesh.vertex_count()) throw Error(source + ": triangle refers to vertex " + std::to_string(id) + " of " +
                                                   std::to_string(mesh.vertex_count()));
    auto vert = [&](uint32_t i) {
        return V3{mesh.positions[3 * size_t(i)], mesh.positions[3 * size_t(i) + 1], mesh.positions[3 * size_t(i) + 2]};
    };
    // Running sums of twice the areas (the factor 1/2 cancels); zero-area triangles are never picked.
    std::vector<double> cum(nt);
    double total = 0;
    for (size_t t = 0; t < nt; ++t) {
        V3 a = vert(mesh.triangles[3 * t]), b = vert(mesh.triangles[3 * t + 1]), c = vert(mesh.triangles[3 * t + 2]);
        total += norm(cross(b - a, c - a));
        cum[t] = total;
    }
    if (!(total > 0) || !std::isfinite(total))
        throw Error(source + ": mesh has no triangle with non-zero area to sample");
    const bool have_normals = mesh.normals.size() == mesh.positions.size();
    HostTensor out({n, 6});
    SplitMix64 rng(seed);
    for (int64_t i = 0; i < n; ++i) {
        double pick = rng.uniform() * total;
        size_t t = size_t(std::upper_bound(cum.begin(), cum.end(), pick) - cum.begin());
        if (t >= nt) t = size_t(std::lower_bound(cum.begin(), cum.end(), total) - cum.begin());  // rounding at the top
        double su = std::sqrt(rng.uniform()), v = rng.uniform();
        double w[3] = {1.0 - su, su * (1.0 - v), su * v};
        uint32_t id[3] = {mesh.triangles[3 * t], mesh.triangles[3 * t + 1], mesh.triangles[3 * t + 2]};
        V3 a = vert(id[0]), b = vert(id[1]), c = vert(id[2]);
        V3 p{w[0] * a.x + w[1] * b.x + w[2] * c.x, w[0] * a.y + w[1] * b.y + w[2] * c.y,
             w[0] * a.z + w[1] * b.z + w[2] * c.z};
        V3 nrm = cross(b - a, c - a);
        if (have_normals) {
            V3 s{0, 0, 0};
            bool all = true;
            for (int k = 0; k < 3; ++k) {
                const float* vn = &mesh.normals[3 * size_t(id[k])];
                all = all && (vn[0] != 0 || vn[1] != 0 || vn[2] != 0);
                s = {s.x + w[k] * vn[0], s.y + w[k] * vn[1], s.z + w[k] * vn[2]};
            }
            // Opposing vertex normals can cancel; the face normal is the fallback then.
            if (all && norm(s) > 1e-6) nrm = s;
        }
        double len = norm(nrm);
        float* o = &out.data[size_t(i) * 6];
        o[0] = float(p.x), o[1] = float(p.y), o[2] = float(p.z);
        o[3] = float(nrm.x / len), o[4] = float(nrm.y / len), o[5] = float(nrm.z / len);
    }
    return out;
}

double surface_area(const TriangleMesh& mesh) {
    double area = 0;
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
        const V3 a = corner(mesh, t, 0);
        area += 0.5 * norm(cross(corner(mesh, t, 1) - a, corner(mesh, t, 2) - a));
    }
    return area;
}

double MeshBounds::largest_side() const { return std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}); }

MeshBounds bounds(const TriangleMesh& mesh) {
    MeshBounds b;
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        b.lo[i % 3] = std::min(b.lo[i % 3], double(mesh.positions[i]));
        b.hi[i % 3] = std::max(b.hi[i % 3], double(mesh.positions[i]));
    }
    return b;
}

double signed_volume(const TriangleMesh& mesh) {
    double v = 0;
    for (size_t t = 0; t < mesh.triangle_count(); ++t) v += dot(corner(mesh, t, 0), cross(corner(mesh, t, 1), corner(mesh, t, 2)));
    return v / 6.0;
}

bool orient_outward(TriangleMesh& mesh) {
    if (!(signed_volume(mesh) < 0)) return false;
    for (size_t t = 0; t < mesh.triangle_count(); ++t) std::swap(mesh.triangles[3 * t + 1], mesh.triangles[3 * t + 2]);
    return true;
}

HostTensor tracker_dense_sample(const TriangleMesh& mesh, const std::string& source) {
    const int64_t n = std::clamp<int64_t>(int64_t(surface_area(mesh) * 4), 20000, 300000);
    return sample_surface(mesh, n, kDefaultSampleSeed + 7, source);
}

}  // namespace vtloc::io
