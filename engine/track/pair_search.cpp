#include "engine/track/pair_search.h"

#include "engine/parallel.h"
#include "engine/track/vec3d.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <utility>

namespace vtloc::track {

namespace {

using namespace v3d;

V row3(const float* p) { return {p[0], p[1], p[2]}; }

// One point per voxel (the first in row order), the voxel doubled until at most cap remain.
std::vector<float> voxel_subset(const std::vector<float>& dense, double voxel, size_t cap) {
    const size_t n = dense.size() / 6;
    std::vector<std::pair<std::array<int64_t, 3>, size_t>> keys(n);
    for (;; voxel *= 2) {
        for (size_t i = 0; i < n; ++i)
            keys[i] = {{int64_t(std::floor(dense[6 * i] / voxel)), int64_t(std::floor(dense[6 * i + 1] / voxel)),
                        int64_t(std::floor(dense[6 * i + 2] / voxel))},
                       i};
        std::sort(keys.begin(), keys.end());
        size_t kept = 0;
        for (size_t i = 0; i < n; ++i) kept += i == 0 || keys[i].first != keys[i - 1].first;
        if (kept <= cap) break;
    }
    std::vector<size_t> rows;
    for (size_t i = 0; i < n; ++i)
        if (i == 0 || keys[i].first != keys[i - 1].first) rows.push_back(keys[i].second);
    std::sort(rows.begin(), rows.end());
    std::vector<float> out;
    out.reserve(rows.size() * 6);
    for (size_t r : rows) out.insert(out.end(), dense.begin() + long(6 * r), dense.begin() + long(6 * r + 6));
    return out;
}

ops::pose::Frame frame(const M& R, const V& t) {
    using P = ops::pose::V3;
    return {P{float(R[0]), float(R[3]), float(R[6])}, P{float(R[1]), float(R[4]), float(R[7])},
            P{float(R[2]), float(R[5]), float(R[8])}, P{float(t[0]), float(t[1]), float(t[2])}};
}

// Each touch's contact and outward normal in the current touch's frame (c, m), and the two
// farthest apart (ri, ji): their distance.
double farthest_pair(const std::vector<ops::pose::Term>& touches, double press, std::vector<V>& c, std::vector<V>& m, size_t& ri,
                     size_t& ji) {
    const size_t n = touches.size();
    c.resize(n), m.resize(n);
    for (size_t k = 0; k < n; ++k) {
        const float* r = touches[k].rel;
        const V z{r[2], r[5], r[8]};
        c[k] = sub(V{touches[k].trel[0], touches[k].trel[1], touches[k].trel[2]}, mul(z, press));
        m[k] = mul(z, -1);
    }
    ri = 0, ji = 1;
    if (n < 2) return 0;
    for (size_t a = 0; a < n; ++a)
        for (size_t b = a + 1; b < n; ++b)
            if (norm(sub(c[b], c[a])) > norm(sub(c[ji], c[ri]))) ri = a, ji = b;
    return norm(sub(c[ji], c[ri]));
}

}  // namespace

PairIndex::PairIndex(const std::vector<float>& dense, double anchor_mm, double partner_mm) {
    if (dense.size() < 12) return;
    anchors_ = voxel_subset(dense, anchor_mm, 20000);
    std::vector<float> p = voxel_subset(dense, partner_mm, 80000);
    const size_t n = p.size() / 6;
    // Cells about four partner voxels wide: a shell query tests every occupied cell's box.
    cell_mm_ = float(std::max(8.0, 4 * partner_mm));
    std::vector<std::pair<std::array<int64_t, 3>, size_t>> keys(n);
    for (size_t i = 0; i < n; ++i)
        keys[i] = {{int64_t(std::floor(p[6 * i] / cell_mm_)), int64_t(std::floor(p[6 * i + 1] / cell_mm_)),
                    int64_t(std::floor(p[6 * i + 2] / cell_mm_))},
                   i};
    std::sort(keys.begin(), keys.end());
    partners_.reserve(p.size());
    for (size_t i = 0; i < n; ++i) {
        if (i == 0 || keys[i].first != keys[i - 1].first) {
            cell_lo_.push_back({float(keys[i].first[0]) * cell_mm_, float(keys[i].first[1]) * cell_mm_, float(keys[i].first[2]) * cell_mm_});
            cell_begin_.push_back(int32_t(i));
        }
        partners_.insert(partners_.end(), p.begin() + long(6 * keys[i].second), p.begin() + long(6 * keys[i].second + 6));
    }
    cell_begin_.push_back(int32_t(n));
}

void PairIndex::shell_pairs(double d, double tol, const std::function<void(int64_t, int64_t)>& f, int64_t a0, int64_t a1) const {
    const double lo = std::max(0.0, d - tol), hi = d + tol, lo2 = lo * lo, hi2 = hi * hi;
    if (a1 < 0 || a1 > n_anchors()) a1 = n_anchors();
    for (int64_t a = a0; a < a1; ++a) {
        const float* pa = anchor(a);
        for (size_t k = 0; k < cell_lo_.size(); ++k) {
            // The box's nearest and farthest points from the anchor bound every partner's distance.
            double near2 = 0, far2 = 0;
            for (int i = 0; i < 3; ++i) {
                const double u = double(cell_lo_[k][size_t(i)]) - pa[i], v = u + cell_mm_;
                const double nu = u > 0 ? u : v < 0 ? -v : 0, fu = std::max(std::abs(u), std::abs(v));
                near2 += nu * nu, far2 += fu * fu;
            }
            if (near2 > hi2 || far2 < lo2) continue;
            for (int32_t b = cell_begin_[k]; b < cell_begin_[k + 1]; ++b) {
                const float* pb = partner(b);
                const double dx = pb[0] - pa[0], dy = pb[1] - pa[1], dz = pb[2] - pa[2], r2 = dx * dx + dy * dy + dz * dz;
                if (r2 >= lo2 && r2 <= hi2) f(a, b);
            }
        }
    }
}

std::vector<Rigid> pair_candidates(const PairIndex& index, const ops::pose::Grid& grid,
                                   const std::vector<ops::pose::Term>& touches, double press, double log_floor,
                                   const std::function<double(const Rigid&)>& fit, const PairSearchOptions& o) {
    const size_t n = touches.size();
    if (index.empty() || n < 3) return {};
    std::vector<V> c, m;
    size_t ri = 0, ji = 1;
    const double d = farthest_pair(touches, press, c, m, ri, ji);
    if (!(d >= o.min_span_mm)) return {};
    const V e = mul(sub(c[ji], c[ri]), 1 / d);
    const double f1 = dot(m[ri], e), f2 = dot(m[ji], e), f3 = dot(m[ri], m[ji]);
    // The third touch: farthest from the pair's line, so its roll arm is longest.
    size_t ki = ri;
    double arm = -1;
    for (size_t k = 0; k < n; ++k) {
        if (k == ri || k == ji) continue;
        const V u = sub(c[k], c[ri]);
        const double h = norm(sub(u, mul(e, dot(u, e))));
        if (h > arm) arm = h, ki = k;
    }
    const V mid_c = mul(add(c[ri], c[ji]), 0.5);
    const float exp_floor = std::exp(float(log_floor));
    auto pose_at = [&](const M& R0, const V& E, double ang, const V& mid) {
        Rigid x;
        x.R = matmul(turn_about(E, ang), R0);
        const V t = sub(mid, rotate(x.R, mid_c));
        x.t = {t[0], t[1], t[2]};
        return x;
    };
    auto third = [&](const Rigid& x) {
        const ops::pose::Frame f = ops::pose::moved(frame(x.R, V{x.t[0], x.t[1], x.t[2]}), touches[ki]);
        return ops::pose::geometry_log(grid, ops::pose::cell_of(grid, f.t), f, float(press), touches[ki].sigma_d, touches[ki].sigma_a,
                                       float(log_floor), exp_floor);
    };
    const double step = o.roll_step_deg * M_PI / 180;
    const int steps = int(std::lround(o.roll_deg / o.roll_step_deg));
    // The anchors in chunks over the threads, each chunk's finds kept apart and joined in
    // chunk order: the same list on any number of threads.
    const int64_t chunk = 256, n_chunks = (index.n_anchors() + chunk - 1) / chunk;
    std::vector<std::vector<std::pair<double, Rigid>>> per_chunk(static_cast<size_t>(n_chunks));
    parallel_for(size_t(n_chunks), o.threads, [&](size_t ci) {
        std::vector<std::pair<double, Rigid>>& found = per_chunk[ci];
        index.shell_pairs(d, o.tol_mm, [&](int64_t a, int64_t b) {
            const float* pa = index.anchor(a);
            const float* pb = index.partner(b);
            const V A = row3(pa), B = row3(pb), na = row3(pa + 3), nb = row3(pb + 3);
            const double dab = norm(sub(B, A));
            if (!(dab > 0)) return;
            const V E = mul(sub(B, A), 1 / dab);
            if (std::abs(dot(na, E) - f1) > o.tol_dot || std::abs(dot(nb, E) - f2) > o.tol_dot || std::abs(dot(na, nb) - f3) > o.tol_dot)
                return;
            // R0: a turn taking e to E; then the roll about E that best lines the two touches'
            // normals up with the points'.
            const M R0 = align(e, E);
            double s = 0, cc = 0;
            for (const auto& [u0, w] : {std::pair<V, V>{m[ri], na}, std::pair<V, V>{m[ji], nb}}) {
                const V u = rotate(R0, u0);
                const V up = sub(u, mul(E, dot(u, E))), wp = sub(w, mul(E, dot(w, E)));
                s += dot(E, cross(up, wp)), cc += dot(up, wp);
            }
            const double psi = std::atan2(s, cc);
            const V mid = mul(add(A, B), 0.5);
            double best_ang = psi, best = -INFINITY;
            for (int k = -steps; k <= steps; ++k) {
                const double ang = psi + k * step, v3 = third(pose_at(R0, E, ang, mid));
                if (v3 > best) best = v3, best_ang = ang;
            }
            for (double h = step / 2; h >= step / 4 - 1e-12; h /= 2)
                for (double sgn : {-1.0, 1.0}) {
                    const double ang = best_ang + sgn * h, v3 = third(pose_at(R0, E, ang, mid));
                    if (v3 > best) best = v3, best_ang = ang;
                }
            if (!(best > float(log_floor))) return;  // the third touch off the surface at every roll
            const Rigid x = pose_at(R0, E, best_ang, mid);
            found.emplace_back(fit(x), x);
        }, int64_t(ci) * chunk, int64_t(ci + 1) * chunk);
    });
    std::vector<std::pair<double, Rigid>> found;
    for (auto& f : per_chunk) found.insert(found.end(), f.begin(), f.end());
    // Best first (ties: the order found), then at most `top` whose places lie 3 mm apart.
    std::vector<size_t> by(found.size());
    std::iota(by.begin(), by.end(), size_t(0));
    std::stable_sort(by.begin(), by.end(), [&](size_t a, size_t b) { return found[a].first > found[b].first; });
    std::vector<Rigid> out;
    for (size_t i : by) {
        if (int(out.size()) >= o.top) break;
        const Rigid& x = found[i].second;
        bool apart = true;
        for (const Rigid& y : out)
            apart = apart && norm(V{x.t[0] - y.t[0], x.t[1] - y.t[1], x.t[2] - y.t[2]}) > 3;
        if (apart) out.push_back(x);
    }
    return out;
}

std::vector<Rigid> pair_candidates(const LazyPairIndex& index, const ops::pose::Grid& grid,
                                   const std::vector<ops::pose::Term>& touches, double press, double log_floor,
                                   const std::function<double(const Rigid&)>& fit, const PairSearchOptions& o) {
    std::vector<V> c, m;
    size_t ri = 0, ji = 1;
    if (touches.size() < 3 || !(farthest_pair(touches, press, c, m, ri, ji) >= o.min_span_mm)) return {};
    return pair_candidates(index.get(), grid, touches, press, log_floor, fit, o);
}

}  // namespace vtloc::track
