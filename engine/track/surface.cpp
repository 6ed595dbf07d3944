#include "engine/track/surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "base/error.h"
#include "engine/cell_key.h"
#include "engine/ops/codebook_math.h"
#include "engine/parallel.h"

namespace vtloc::track {

namespace {

using D3 = std::array<double, 3>;

std::array<int64_t, 3> cell_of(const float* p, const D3& lo, double h) {
    std::array<int64_t, 3> k;
    for (int i = 0; i < 3; ++i) k[size_t(i)] = int64_t(std::floor((double(p[i]) - lo[size_t(i)]) / h));
    return k;
}

int64_t key_of(const float* p, const D3& lo, double h) {
    const auto k = cell_of(p, lo, h);
    return cell_key(k[0], k[1], k[2]);
}

// Interleaves the bits of a cube's indices (z-order): cubes near in space get near codes.
uint64_t morton(const float* p, const D3& lo, double h) {
    const auto c = cell_of(p, lo, h);
    uint64_t code = 0, k[3];
    for (int i = 0; i < 3; ++i) k[i] = uint64_t(std::max<int64_t>(0, c[size_t(i)]));
    for (int bit = 0; bit < 21; ++bit)
        for (int i = 0; i < 3; ++i) code |= ((k[i] >> bit) & 1u) << (3 * bit + i);
    return code;
}

// One sample per occupied cube of side h: the dense point nearest the cube's
// centre (lowest index on a tie), and a second where the cube also holds points
// whose normals oppose the first's (a thin part's far face, which would otherwise
// have no hypothesis there). With `zorder`, in z-order of the cubes, so that samples
// near in index are near in space (the evidence shader's lanes then read nearby
// cells); the spacing's bisection below needs only how many.
// The cubes' keys go in a flat table (open addressing): the bisection calls this ~25
// times on every dense point, and std::unordered_map's nodes and the z-order sort of
// each try took ~30 % of a tracker's making (a 224k-point mug: 460 ms).
std::vector<int64_t> pick_samples(const std::vector<float>& dense, const D3& lo, double h, bool zorder) {
    const int64_t D = int64_t(dense.size() / 6);
    int bits = 4;
    while ((int64_t(1) << bits) < 2 * D) ++bits;
    const uint64_t mask = (uint64_t(1) << bits) - 1;
    std::vector<int64_t> table_key(size_t(mask + 1), -1);  // cell_key is never negative
    std::vector<uint32_t> table_slot(size_t(mask + 1));
    std::vector<uint32_t> slot_of(static_cast<size_t>(D));
    std::vector<int64_t> best, far;
    std::vector<double> best_d, far_d, centre_d(static_cast<size_t>(D));
    for (int64_t i = 0; i < D; ++i) {
        const float* p = &dense[size_t(i * 6)];
        const auto c = cell_of(p, lo, h);
        double d = 0;  // to the cube's centre
        for (size_t k = 0; k < 3; ++k) {
            const double e = double(p[k]) - (lo[k] + (double(c[k]) + 0.5) * h);
            d += e * e;
        }
        centre_d[size_t(i)] = d;
        const int64_t key = cell_key(c[0], c[1], c[2]);
        uint64_t t = (uint64_t(key) * 0x9E3779B97F4A7C15ull) >> (64 - bits);
        while (table_key[t] >= 0 && table_key[t] != key) t = (t + 1) & mask;
        if (table_key[t] < 0) {
            table_key[t] = key, table_slot[t] = uint32_t(best.size());
            best.push_back(i), best_d.push_back(d);
        } else if (d < best_d[table_slot[t]]) {
            best[table_slot[t]] = i, best_d[table_slot[t]] = d;
        }
        slot_of[size_t(i)] = table_slot[t];
    }
    far.assign(best.size(), -1);
    far_d.assign(best.size(), INFINITY);
    for (int64_t i = 0; i < D; ++i) {
        const float* p = &dense[size_t(i * 6)];
        const size_t c = slot_of[size_t(i)];
        const float* m = &dense[size_t(best[c] * 6)];
        if (!(p[3] * m[3] + p[4] * m[4] + p[5] * m[5] < 0)) continue;
        if (centre_d[size_t(i)] < far_d[c]) far[c] = i, far_d[c] = centre_d[size_t(i)];
    }
    for (int64_t i : far)
        if (i >= 0) best.push_back(i);
    if (!zorder) return best;
    std::vector<std::pair<uint64_t, int64_t>> order;
    for (int64_t i : best) order.push_back({morton(&dense[size_t(i * 6)], lo, h), i});
    std::sort(order.begin(), order.end());
    for (size_t k = 0; k < order.size(); ++k) best[k] = order[k].second;
    return best;
}

// For every cell within `band` of a point, the nearest point (lowest index on a tie),
// into slot `slot` of `cells` ([V, 2]). With `opposes`, only points whose normal (at
// 3..5 of the point) turns away from that of the point in slot 0: a thin part's far face.
// Slabs of z run on up to `threads` threads (SurfaceOptions::threads): each cell is
// written by one slab, its points visited in index order, so the grid is the same
// on any number of threads.
void splat(std::vector<int32_t>& cells, int slot, const float* pts, int64_t n, int64_t stride, const Surface& s,
           double band, int threads, bool opposes = false) {
    std::vector<float> best(cells.size() / 2, std::numeric_limits<float>::infinity());
    // Both points within the band of one cell: at most 2 bands apart (a cell's width spare).
    const std::vector<char> may = opposes ? may_oppose(pts, n, stride, s, 2 * band + s.voxel) : std::vector<char>();
    const int r = int(std::ceil(band / s.voxel));
    const float band2 = float(band * band);
    const int nz = s.dims[2], slabs = threads == 1 ? 1 : std::min(nz, 16);  // each slab scans every point
    parallel_for(size_t(slabs), threads, [&](size_t slab) {
        const int z_begin = int(int64_t(slab) * nz / slabs), z_end = int(int64_t(slab + 1) * nz / slabs);
        for (int64_t i = 0; i < n; ++i) {
            if (opposes && !may[size_t(i)]) continue;
            const float* p = pts + i * stride;
            int c[3];
            for (int k = 0; k < 3; ++k) c[k] = int(std::floor((p[k] - s.origin[size_t(k)]) / s.voxel));
            const int z_lo = std::max({0, c[2] - r, z_begin}), z_hi = std::min({nz - 1, c[2] + r, z_end - 1});
            if (z_lo > z_hi) continue;
            // Cell x's squared distance, summed as always; it only grows away from the point's own
            // cell (float rounding is monotonic), so each row stops at the first cell past the band,
            // and a row or plane whose (y, z) terms alone pass it is skipped: the same cells as the
            // whole cube, in under half the visits.
            auto visit = [&](int x, size_t row, float yz_y, float yz_z) {
                const float qx = s.origin[0] + (float(x) + 0.5f) * s.voxel;
                const float d = (qx - p[0]) * (qx - p[0]) + yz_y + yz_z;
                if (d > band2) return false;
                const size_t cell = row + size_t(x);
                if (!(d < best[cell])) return true;
                if (opposes) {  // after the distance: most cells fail it without this read
                    const int32_t o = cells[2 * cell];
                    if (o < 0) return true;
                    const float* m = pts + int64_t(o) * stride + 3;
                    if (!(p[3] * m[0] + p[4] * m[1] + p[5] * m[2] < 0)) return true;
                }
                best[cell] = d, cells[2 * cell + size_t(slot)] = int32_t(i);
                return true;
            };
            const int x_lo = std::max(0, c[0] - r), x_hi = std::min(s.dims[0] - 1, c[0] + r);
            const int x0 = std::clamp(c[0], x_lo, x_hi);
            for (int z = z_lo; z <= z_hi; ++z) {
                const float qz = s.origin[2] + (float(z) + 0.5f) * s.voxel, yz_z = (qz - p[2]) * (qz - p[2]);
                if (yz_z > band2) continue;
                for (int y = std::max(0, c[1] - r); y <= std::min(s.dims[1] - 1, c[1] + r); ++y) {
                    const float qy = s.origin[1] + (float(y) + 0.5f) * s.voxel, yz_y = (qy - p[1]) * (qy - p[1]);
                    if (yz_y + yz_z > band2) continue;  // (dx^2 + yz_y) + yz_z >= yz_y + yz_z, rounded
                    const size_t row = (size_t(z) * size_t(s.dims[1]) + size_t(y)) * size_t(s.dims[0]);
                    visit(x0, row, yz_y, yz_z);  // the nearest column may be out of the band: the others still run
                    for (int x = x0 + 1; x <= x_hi && visit(x, row, yz_y, yz_z); ++x) {}
                    for (int x = x0 - 1; x >= x_lo && visit(x, row, yz_y, yz_z); --x) {}
                }
            }
        }
    });
}

}  // namespace

// Per cube of side `reach`, the bounds of its points' normals; a point whose normal has a
// dot product of at least 1e-4 with every normal those bounds allow in its 27 cubes cannot
// oppose any (float rounding is ~1e-7 here). The far-face pass stores a point only in a
// cell whose slot-0 point opposes it, both within the cell's band, so it skips these: on
// most of a surface the normals nearby agree, and the pass had checked every point against
// every cell of its band (potato_tour.ply: a tracker's making 0.50 -> 0.24 s; a thin-walled
// mug keeps most of its points).
std::vector<char> may_oppose(const float* pts, int64_t n, int64_t stride, const Surface& s, double reach) {
    std::array<int, 3> dims;
    for (int k = 0; k < 3; ++k) dims[size_t(k)] = std::max(1, int(std::ceil(double(s.dims[size_t(k)]) * s.voxel / reach)));
    auto cube = [&](const float* p) {
        std::array<int, 3> c;
        for (int k = 0; k < 3; ++k)
            c[size_t(k)] = int(std::clamp(std::floor((double(p[k]) - s.origin[size_t(k)]) / reach), 0.0, double(dims[size_t(k)] - 1)));
        return c;
    };
    const size_t C = size_t(dims[0]) * size_t(dims[1]) * size_t(dims[2]);
    std::vector<std::array<float, 6>> bounds(C, {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY});
    auto index = [&](const std::array<int, 3>& c) { return (size_t(c[2]) * size_t(dims[1]) + size_t(c[1])) * size_t(dims[0]) + size_t(c[0]); };
    for (int64_t i = 0; i < n; ++i) {
        const float* p = pts + i * stride;
        auto& b = bounds[index(cube(p))];
        for (int k = 0; k < 3; ++k) b[size_t(k)] = std::min(b[size_t(k)], p[3 + k]), b[size_t(3 + k)] = std::max(b[size_t(3 + k)], p[3 + k]);
    }
    auto opposable = [&](const float* p) {
        const auto c = cube(p);
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const std::array<int, 3> q{c[0] + dx, c[1] + dy, c[2] + dz};
                    if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= dims[0] || q[1] >= dims[1] || q[2] >= dims[2]) continue;
                    const auto& b = bounds[index(q)];
                    if (b[0] > b[3]) continue;  // empty
                    double least = 0;
                    for (int k = 0; k < 3; ++k) least += std::min(double(p[3 + k]) * b[size_t(k)], double(p[3 + k]) * b[size_t(3 + k)]);
                    if (least < 1e-4) return true;
                }
        return false;
    };
    std::vector<char> may(static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i) may[size_t(i)] = opposable(pts + i * stride);
    return may;
}

D3 tangent_of(const D3& a) {
    D3 e = std::abs(a[0]) <= std::abs(a[1]) && std::abs(a[0]) <= std::abs(a[2]) ? D3{1, 0, 0}
           : std::abs(a[1]) <= std::abs(a[2])                                   ? D3{0, 1, 0}
                                                                                : D3{0, 0, 1};
    const double d = e[0] * a[0] + e[1] * a[1] + e[2] * a[2];
    D3 t{e[0] - d * a[0], e[1] - d * a[1], e[2] - d * a[2]};
    const double n = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    return {t[0] / n, t[1] / n, t[2] / n};
}

int64_t Surface::cell_of(const float* q) const { return ops::pose::cell_of(grid(), {q[0], q[1], q[2]}); }

Surface build_surface(const HostTensor& dense, bool from_mesh, const SurfaceOptions& o, const std::string& source) {
    if (dense.shape.size() != 2 || dense.shape[1] != 6 || dense.shape[0] == 0)
        throw Error(source + ": the filter needs surface points with normals [N > 0, 6], got " + shape_str(dense.shape));
    if (o.n_spin < 1 || o.target_hypotheses < o.n_spin || o.max_cells < 8 || !(o.band_mm > 0) || !(o.min_voxel_mm > 0))
        throw Error("surface options: n_spin >= 1, target_hypotheses >= n_spin, max_cells >= 8 and positive widths");
    const int64_t D = dense.shape[0];
    Surface s;
    s.from_mesh = from_mesh;
    s.dense = dense.data;
    D3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (int64_t i = 0; i < D; ++i) {
        float* p = &s.dense[size_t(i * 6)];
        double nn = 0;
        for (int k = 0; k < 6; ++k)
            if (!std::isfinite(p[k])) throw Error(source + ": point " + std::to_string(i) + " is not finite");
        for (int k = 0; k < 3; ++k) nn += double(p[3 + k]) * p[3 + k], lo[size_t(k)] = std::min(lo[size_t(k)], double(p[k])),
                                     hi[size_t(k)] = std::max(hi[size_t(k)], double(p[k]));
        if (!(nn > 1e-12)) throw Error(source + ": point " + std::to_string(i) + " has a zero normal");
        for (int k = 0; k < 3; ++k) p[3 + k] = float(p[3 + k] / std::sqrt(nn));
    }
    const D3 ext{hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    s.diameter = std::sqrt(ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]);

    // Spacing: bisect h (on a log scale) until the samples are about target / NS.
    if (!o.candidates.empty()) {
        if (o.candidates.size() % 3) throw Error(source + ": candidates must be x, y, z triples");
        for (size_t c = 0; c < o.candidates.size(); c += 3) {
            const float* q = &o.candidates[c];
            if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2]))
                throw Error(source + ": candidate " + std::to_string(c / 3 + 1) + " is not finite");
            int64_t best = 0;
            double best_d = INFINITY;
            for (int64_t i = 0; i < D; ++i) {
                const float* p = &s.dense[size_t(i * 6)];
                const double d = (double(p[0]) - q[0]) * (double(p[0]) - q[0]) + (double(p[1]) - q[1]) * (double(p[1]) - q[1]) +
                                 (double(p[2]) - q[2]) * (double(p[2]) - q[2]);
                if (d < best_d) best_d = d, best = i;
            }
            const float* n = &s.dense[size_t(best * 6 + 3)];
            const D3 t1 = tangent_of(D3{-double(n[0]), -double(n[1]), -double(n[2])});
            s.samples.insert(s.samples.end(), q, q + 3);
            s.samples.insert(s.samples.end(), n, n + 3);
            for (double v : t1) s.samples.push_back(float(v));
        }
        s.spacing_mm = 0;  // the truth is among the candidates: no grid allowance in distance
        s.from_candidates = true;
    }
    const double want = double(o.target_hypotheses) / o.n_spin;
    double h_lo = std::max(1e-3, s.diameter * 1e-4), h_hi = std::max(2 * s.diameter, 1e-2);
    std::vector<int64_t> picked;
    for (int it = 0; it < 24 && o.candidates.empty(); ++it) {
        const double h = std::sqrt(h_lo * h_hi);
        picked = pick_samples(s.dense, lo, h, false);
        if (double(picked.size()) > want) h_lo = h;
        else h_hi = h;
    }
    if (o.candidates.empty()) {
        s.spacing_mm = h_hi;
        picked = pick_samples(s.dense, lo, s.spacing_mm, true);
    }
    for (int64_t i : picked) {
        const float* p = &s.dense[size_t(i * 6)];
        const D3 t1 = tangent_of(D3{-double(p[3]), -double(p[4]), -double(p[5])});
        s.samples.insert(s.samples.end(), p, p + 6);
        for (double v : t1) s.samples.push_back(float(v));
    }
    if (s.n_samples() >= (int64_t(1) << 24))  // pose_evidence holds sample indices as floats
        throw Error(source + ": " + std::to_string(s.n_samples()) + " hypothesis samples, at most 2^24");
    s.spins = ops::book::spin_table(o.n_spin);

    // Grid: the box grown by the band, in cells no smaller than min_voxel, at most max_cells.
    const double margin = o.band_mm + 1.0;
    const double vol = (ext[0] + 2 * margin) * (ext[1] + 2 * margin) * (ext[2] + 2 * margin);
    s.voxel = float(std::max(o.min_voxel_mm, std::cbrt(vol / double(o.max_cells)) * 1.0001));
    int64_t cells = 0;
    for (int grow = 0; grow < 64; ++grow, s.voxel *= 1.02f) {  // the ceilings may push past max_cells
        cells = 1;
        for (int k = 0; k < 3; ++k) {
            s.origin[size_t(k)] = float(lo[size_t(k)] - margin);
            s.dims[size_t(k)] = int32_t(std::ceil((ext[size_t(k)] + 2 * margin) / s.voxel));
            cells *= s.dims[size_t(k)];
        }
        if (cells <= o.max_cells) break;
    }
    if (cells > o.max_cells) throw Error(source + ": the lookup grid would need " + std::to_string(cells) + " cells");
    s.cells.assign(size_t(2 * cells), -1);
    const double band = std::max(o.band_mm, double(s.voxel));
    splat(s.cells, 0, s.dense.data(), D, 6, s, band, o.threads);
    splat(s.cells, 1, s.dense.data(), D, 6, s, band, o.threads, true);
    // Each dense point's sample: of the samples nearest its cell's centre (and their
    // far-face counterparts), the one on the point's own face.
    std::vector<int32_t> near(size_t(2 * cells), -1);
    splat(near, 0, s.samples.data(), s.n_samples(), 9, s, std::max(band, 1.5 * s.spacing_mm), o.threads);
    splat(near, 1, s.samples.data(), s.n_samples(), 9, s, std::max(band, 1.5 * s.spacing_mm), o.threads, true);
    s.dense_sample.assign(size_t(D), -1);
    for (int64_t i = 0; i < D; ++i) {
        const float* p = &s.dense[size_t(6 * i)];
        const int64_t c = s.cell_of(p);
        if (c < 0 || near[size_t(2 * c)] < 0) continue;
        const int32_t a = near[size_t(2 * c)], b = near[size_t(2 * c + 1)];
        const float* n = &s.samples[size_t(9 * a + 3)];
        s.dense_sample[size_t(i)] = b >= 0 && p[3] * n[0] + p[4] * n[1] + p[5] * n[2] < 0 ? b : a;
    }
    return s;
}

}  // namespace vtloc::track

namespace vtloc::track {

HostTensor slack_neighbours(const Surface& s, int kn, double radius) {
    const int64_t S = s.n_samples(), NS = s.n_spin();
    if (kn < 1) throw Error("slack_neighbours: kn must be >= 1, got " + std::to_string(kn));
    if (!std::isfinite(radius)) throw Error("slack_neighbours: the radius must be finite, got " + std::to_string(radius));
    HostTensor nb({S, int64_t(kn), 3}, std::vector<float>(size_t(S * kn * 3), -1.0f));
    if (!(radius > 0) || S == 0) return nb;
    // Bucket the samples in cubes of at least the radius: a sample's neighbours lie in the 27 around its
    // own. At most 2^19 cubes along the extent, whatever the (finite) radius: indices stay far from int64's
    // limits and from cell_key's 21 bits (where distinct cubes would share buckets).
    D3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (int64_t i = 0; i < S; ++i)
        for (int k = 0; k < 3; ++k) {
            lo[size_t(k)] = std::min(lo[size_t(k)], double(s.samples[size_t(9 * i + k)]));
            hi[size_t(k)] = std::max(hi[size_t(k)], double(s.samples[size_t(9 * i + k)]));
        }
    const double h = std::max({radius, (hi[0] - lo[0]) / 524288.0, (hi[1] - lo[1]) / 524288.0, (hi[2] - lo[2]) / 524288.0});
    for (double& l : lo) l -= h;
    std::unordered_map<int64_t, std::vector<int64_t>> bins;
    for (int64_t i = 0; i < S; ++i) bins[key_of(&s.samples[size_t(9 * i)], lo, h)].push_back(i);
    const double step = 2 * M_PI / double(NS), r2 = radius * radius;
    std::vector<std::pair<double, int64_t>> near;
    for (int64_t i = 0; i < S; ++i) {
        const float* a = &s.samples[size_t(9 * i)];
        near.clear();
        // The 27 integer cells around a's own: a probe at a +- radius could round into a's cell again.
        const auto c = cell_of(a, lo, h);
        for (int64_t dz = -1; dz <= 1; ++dz)
            for (int64_t dy = -1; dy <= 1; ++dy)
                for (int64_t dx = -1; dx <= 1; ++dx) {
                    auto it = bins.find(cell_key(c[0] + dx, c[1] + dy, c[2] + dz));
                    if (it == bins.end()) continue;
                    for (int64_t j : it->second) {
                        const float* b = &s.samples[size_t(9 * j)];
                        const double d2 = (double(a[0]) - b[0]) * (double(a[0]) - b[0]) + (double(a[1]) - b[1]) * (double(a[1]) - b[1]) +
                                          (double(a[2]) - b[2]) * (double(a[2]) - b[2]);
                        const double nn = double(a[3]) * b[3] + double(a[4]) * b[4] + double(a[5]) * b[5];
                        if (j != i && d2 <= r2 && nn >= kSlackMinCos) near.push_back({d2, j});
                    }
                }
        std::sort(near.begin(), near.end());  // nearest first, lower index on a tie
        for (size_t k = 0; k < near.size() && k < size_t(kn); ++k) {
            const float* b = &s.samples[size_t(9 * near[k].second)];
            // The spin of s' whose x axis is nearest s's spin 0 (x = t1): its angle in s''s basis (t1', z' x t1').
            const double z[3] = {-b[3], -b[4], -b[5]}, t1[3] = {b[6], b[7], b[8]};
            const double t2[3] = {z[1] * t1[2] - z[2] * t1[1], z[2] * t1[0] - z[0] * t1[2], z[0] * t1[1] - z[1] * t1[0]};
            const double phi = std::atan2(a[6] * t2[0] + a[7] * t2[1] + a[8] * t2[2], a[6] * t1[0] + a[7] * t1[1] + a[8] * t1[2]);
            const int64_t off = ((int64_t(std::lround(phi / step)) % NS) + NS) % NS;
            float* r = &nb.data[size_t((i * kn + int64_t(k)) * 3)];
            r[0] = float(near[k].second);
            r[1] = float(near[k].first);
            r[2] = float(off);
        }
    }
    return nb;
}

}  // namespace vtloc::track
