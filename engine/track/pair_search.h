#pragma once
// The pair search (docs/multitouch.md, "Pair search"): candidates for a window whose touches
// neither the grid's modes nor their registrations put on the surface. At lever arms of
// 100-200 mm the truth's basin is narrower than the grid's spacing and spin step, so no
// hypothesis starts in it; but the window's two farthest contacts, at a known distance with
// known axes, can sit only on pairs of surface points that far apart whose normals make the
// same angles. Each such pair fixes a pose up to a roll about the line between them, which a
// third touch fixes; the whole window then scores each pose. Exact to the surface sampling
// (1.5 mm), not to the grid's.
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "engine/ops/pose_evidence.h"
#include "engine/rigid.h"
#include "engine/track/lazy_index.h"

namespace vtloc::track {

class PairIndex {
public:
    PairIndex() = default;
    // dense [D, 6]: point, outward unit normal. Anchors one per anchor_mm voxel, partners one
    // per partner_mm voxel (each voxel's first point in dense order; the voxels grow where
    // a set would pass 20,000 anchors or 80,000 partners), the partners bucketed in cells.
    explicit PairIndex(const std::vector<float>& dense, double anchor_mm = 3, double partner_mm = 1.5);
    bool empty() const { return anchors_.empty(); }
    int64_t n_anchors() const { return int64_t(anchors_.size() / 6); }
    int64_t n_partners() const { return int64_t(partners_.size() / 6); }
    uint64_t bytes() const { return 4 * (anchors_.size() + partners_.size() + cell_begin_.size()) + 12 * cell_lo_.size(); }
    // Calls f(a, b) for every anchor a in [a0, a1) (default: all) and partner b with
    // | |p_b - p_a| - d | <= tol (rows of anchors() and partners()), in anchor order, each
    // anchor's partners in the cells' order.
    void shell_pairs(double d, double tol, const std::function<void(int64_t, int64_t)>& f, int64_t a0 = 0, int64_t a1 = -1) const;
    const float* anchor(int64_t a) const { return &anchors_[size_t(6 * a)]; }
    const float* partner(int64_t b) const { return &partners_[size_t(6 * b)]; }

private:
    std::vector<float> anchors_, partners_;  // [n, 6], the partners sorted by cell
    std::vector<std::array<float, 3>> cell_lo_;  // each occupied cell's corner
    std::vector<int32_t> cell_begin_;            // its partners [begin[k], begin[k + 1])
    float cell_mm_ = 8;
};

// A PairIndex made on first use: most trackers never run the pair search (it needs a window
// spanning min_span_mm), so they should not pay for its index (tens of milliseconds and about
// a megabyte per object).
using LazyPairIndex = LazyIndex<PairIndex>;

struct PairSearchOptions {
    double tol_mm = 1.5;      // the pair's distance against the contacts' (the partners' voxel)
    double tol_dot = 0.2;     // each of the three normal angles' cosines (tilts of a few degrees)
    double roll_deg = 20;     // the roll scanned about the normals' own, each way
    double roll_step_deg = 2; // then refined to a quarter of this
    double min_span_mm = 60;  // shorter windows: none (fitted on train windows: docs/multitouch.md)
    int top = 8;              // candidates returned, best first, 3 mm apart
    int threads = 1;          // host threads (parallel_for's; the result does not depend on it)
};

// Candidates for the current touch's pose. touches: every touch of the window as a term (its
// pose in the current touch's frame and its widths; the current one's rel the identity);
// fit: the window's fit of a pose (the refinement's). Empty where the span is too short or no
// pair matches.
std::vector<Rigid> pair_candidates(const PairIndex& index, const ops::pose::Grid& grid,
                                   const std::vector<ops::pose::Term>& touches, double press, double log_floor,
                                   const std::function<double(const Rigid&)>& fit, const PairSearchOptions& o = {});
// The same from an index made on first use: a window spanning less than min_span_mm returns
// before the index is asked for, so a tracker whose windows never span that never builds it.
std::vector<Rigid> pair_candidates(const LazyPairIndex& index, const ops::pose::Grid& grid,
                                   const std::vector<ops::pose::Term>& touches, double press, double log_floor,
                                   const std::function<double(const Rigid&)>& fit, const PairSearchOptions& o = {});

}  // namespace vtloc::track
