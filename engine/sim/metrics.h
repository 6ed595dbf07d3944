#pragma once
// The paper's localisation metrics (SPEC section 5, docs/eval.md): per-touch
// error, ND, rank of the ground-truth candidate, MPE of a heat-map, the
// per-object-then-over-objects aggregation, and the analytic Chance baseline.
// Pure host code in double: no GPU, no files.
#include <array>
#include <string>
#include <vector>

#include "engine/tensor.h"

namespace vtloc::sim {

using Point3 = std::array<double, 3>;

// An object as the metrics see it: its cloud P, candidates S^c (object units),
// the normalised frame of P and D (largest distance between two points of P).
struct MetricObject {
    std::vector<Point3> points;      // P, object units
    std::vector<Point3> candidates;  // S^c, object units
    Point3 centre{};                 // mean of P
    double scale = 1;                // max ||p - centre||
    double diameter = 0;             // D
    std::vector<Point3> points_n, candidates_n;  // the same in the normalised frame

    // cloud: N x (>= 3), candidates: K x 3 (object units). Throws vtloc::Error
    // for an empty or degenerate cloud (all points coincide) or no candidate.
    static MetricObject make(const HostTensor& cloud, const HostTensor& candidates);
    Point3 normalise(const Point3& p) const;
};

// Largest distance between two points (exact, O(N^2)).
double diameter(const std::vector<Point3>& points);

// Candidate indices sorted by ||c_j - q||^2 ascending (ties to the lower index);
// q and the candidates in the same frame.
std::vector<int> order_by_distance(const std::vector<Point3>& candidates, const Point3& q);
// Index of the candidate nearest to q (ties to the lower index).
int nearest(const std::vector<Point3>& candidates, const Point3& q);

// SPEC section 3 heat-map over the normalised cloud from ranked centres
// (centres[0] has rank 1): nearest centre w (lowest rank on a tie),
// exp(-d) / w, min-max normalised (zeros when flat).
std::vector<float> topk_heatmap(const std::vector<Point3>& points_n, const std::vector<Point3>& centres_n);
// The ground-truth map: min-max normalised exp(-||p - c^gt||), normalised frame.
std::vector<float> gt_heatmap(const std::vector<Point3>& points_n, const Point3& gt_n);
// mean |a - b| (equal sizes).
double mean_abs_diff(const std::vector<float>& a, const std::vector<float>& b);

struct TouchMetrics {
    double error_mm = 0, nd = 0;  // nd in %
    int rank = 0;                 // 1-based rank of the ground-truth candidate
    double mpe = 0;
};

// One touch: prediction `pred` and truth `gt` in object units. `ranking` is the
// method's candidate order, best first (empty = by distance to pred in the
// normalised frame, docs/eval.md); `heat` its heat-map over P (empty = the
// SPEC section 3 map of the first `topk` of that order).
TouchMetrics touch_metrics(const MetricObject& o, const Point3& pred, const Point3& gt, std::vector<int> ranking = {},
                           const std::vector<float>& heat = {}, int topk = 5);

// The analytic Chance baseline: the exact expectation of touch_metrics over a
// prediction drawn uniformly from the candidates (each candidate taken as the
// prediction once; rank is then an expected value and top-1/top-5 are the
// fractions of candidates that score). `heats` caches the per-candidate
// heat-maps (chance_heatmaps), which do not depend on the touch.
struct ChanceMetrics {
    double error_mm = 0, nd = 0, top1 = 0, top5 = 0, mpe = 0;  // top1/top5 as fractions
};
std::vector<std::vector<float>> chance_heatmaps(const MetricObject& o, int topk);
ChanceMetrics chance_metrics(const MetricObject& o, const Point3& gt, const std::vector<std::vector<float>>& heats,
                             int topk);

// A touch's contribution to a row: error, ND, hit indicators (0/1 or, for
// Chance, probabilities) and MPE.
struct TouchScore {
    double error_mm = 0, nd = 0, top1 = 0, top5 = 0, mpe = 0;
};
TouchScore score(const TouchMetrics& m);
TouchScore score(const ChanceMetrics& m);

// A table row: averaged per object first, then over the objects (objects with
// no touch do not count). top1, top5 and nd are percentages.
struct RowMetrics {
    int objects = 0, touches = 0;
    double mm = 0, nd = 0, top1 = 0, top5 = 0, mpe = 0;
};
RowMetrics aggregate(const std::vector<std::vector<TouchScore>>& per_object);

}  // namespace vtloc::sim
